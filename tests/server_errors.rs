//! Misbehaving clients get the documented error, and the server keeps
//! serving everyone else.

#[path = "server_support.rs"]
mod support;

use naosoccer_client::{Client, ClientError};
use naosoccer_proto::frame;
use naosoccer_proto::msg::{
    ActionMsg, ClientMsg, CreateMatch, ErrorCode, ErrorMsg, Hello, MatchId, MatchState, Mode,
    Player, PlayerAction, ServerMsg, Version,
};
use naosoccer_proto::{Action, Team};
use support::*;
use tokio::net::TcpStream;

fn p(n: usize) -> Player {
    Player::new(n).unwrap()
}

async fn expect_error(c: &mut Client, code: ErrorCode, fatal: bool) -> ErrorMsg {
    match c.recv().await.unwrap() {
        ServerMsg::Error(e) => {
            assert_eq!(e.code, code, "{e}");
            assert_eq!(e.fatal, fatal, "{e}");
            e
        }
        other => panic!("expected a {code} error, got {other:?}"),
    }
}

async fn expect_closed(c: &mut Client) {
    assert!(matches!(c.recv().await, Err(ClientError::Closed)));
}

/// The server still answers: a fresh connection pings.
async fn still_serving(addr: &str) {
    let mut c = Client::connect(addr, "probe").await.unwrap();
    assert_eq!(c.ping(99).await.unwrap(), 99);
}

#[tokio::test]
async fn version_mismatch_is_fatal_unimplemented() {
    let server = start(config(10)).await;
    let stream = TcpStream::connect(server.addr).await.unwrap();
    let hello = Hello {
        version: Version { major: 2, minor: 0 },
        ..Hello::new("future")
    };
    let err = Client::handshake(stream, &hello).await.unwrap_err();
    match err {
        ClientError::Server(e) => {
            assert_eq!(e.code, ErrorCode::Unimplemented);
            assert!(e.fatal);
            assert_eq!(e.in_reply_to.as_deref(), Some("hello"));
            assert!(e.message.contains("1.x"), "{}", e.message);
        }
        other => panic!("{other}"),
    }
    // A newer minor version is fine.
    let stream = TcpStream::connect(server.addr).await.unwrap();
    let hello = Hello {
        version: Version { major: 1, minor: 9 },
        ..Hello::new("newer minor")
    };
    Client::handshake(stream, &hello).await.unwrap();
    // Another protocol altogether.
    let stream = TcpStream::connect(server.addr).await.unwrap();
    let hello = Hello {
        protocol: "simspark".into(),
        ..Hello::new("x")
    };
    assert_eq!(
        Client::handshake(stream, &hello).await.unwrap_err().code(),
        Some(ErrorCode::InvalidArgument)
    );
    still_serving(&server.addr()).await;
    server.stop().await;
}

#[tokio::test]
async fn request_before_hello_is_fatal() {
    let server = start(config(10)).await;
    let stream = TcpStream::connect(server.addr).await.unwrap();
    let (mut r, mut w) = stream.into_split();
    use tokio::io::{AsyncReadExt, AsyncWriteExt};
    w.write_all(&frame::encode(&serde_json::json!({"type": "ping"})).unwrap())
        .await
        .unwrap();
    let mut len = [0u8; 4];
    r.read_exact(&mut len).await.unwrap();
    let mut body = vec![0u8; u32::from_be_bytes(len) as usize];
    r.read_exact(&mut body).await.unwrap();
    let msg: ServerMsg = serde_json::from_slice(&body).unwrap();
    assert!(matches!(
        msg,
        ServerMsg::Error(ErrorMsg {
            code: ErrorCode::FailedPrecondition,
            fatal: true,
            ..
        })
    ));
    assert_eq!(
        r.read(&mut len).await.unwrap(),
        0,
        "closed after the fatal error"
    );
    still_serving(&server.addr()).await;
    server.stop().await;
}

#[tokio::test]
async fn frame_over_the_cap_is_refused_before_reading_it() {
    let mut cfg = config(10);
    cfg.max_frame = 4096;
    let server = start(cfg).await;
    let mut c = Client::connect(server.addr().as_str(), "big")
        .await
        .unwrap();
    assert_eq!(c.welcome().max_frame, 4096);
    // Only the header: the server must not wait for (or allocate) 1 MiB.
    c.send_raw(&(1u32 << 20).to_be_bytes()).await.unwrap();
    let e = expect_error(&mut c, ErrorCode::ResourceExhausted, true).await;
    assert!(e.message.contains("4096"), "{}", e.message);
    expect_closed(&mut c).await;
    still_serving(&server.addr()).await;
    server.stop().await;
}

#[tokio::test]
async fn malformed_json_and_unknown_types_keep_the_connection() {
    let server = start(config(10)).await;
    let mut c = Client::connect(server.addr().as_str(), "sloppy")
        .await
        .unwrap();
    for bad in [
        &b"{\"type\": \"ping\","[..],
        b"[1,2,3]",
        b"{\"nonce\": 3}",
        b"\xff\xfe",
        b"{\"type\":\"join\",\"team\":\"green\"}",
    ] {
        let mut f = (bad.len() as u32).to_be_bytes().to_vec();
        f.extend_from_slice(bad);
        c.send_raw(&f).await.unwrap();
        expect_error(&mut c, ErrorCode::InvalidArgument, false).await;
    }
    c.send_raw(&frame::encode(&serde_json::json!({"type": "teleport", "x": 1})).unwrap())
        .await
        .unwrap();
    let e = expect_error(&mut c, ErrorCode::Unimplemented, false).await;
    assert_eq!(e.in_reply_to.as_deref(), Some("unknown"));
    // Unknown fields are ignored.
    c.send_raw(
        &frame::encode(&serde_json::json!({"type": "ping", "nonce": 5, "colour": "red"})).unwrap(),
    )
    .await
    .unwrap();
    assert!(matches!(c.recv().await.unwrap(), ServerMsg::Pong(p) if p.nonce == 5));
    assert_eq!(c.ping(6).await.unwrap(), 6, "same connection still served");
    server.stop().await;
}

#[tokio::test]
async fn tokens_guard_teams_and_match_creation() {
    let server = start(config(10)).await;
    let mut c = Client::connect(server.addr().as_str(), "intruder")
        .await
        .unwrap();
    let e = c
        .join(Some(MatchId(1)), Team::Red, BLUE, &[p(0)])
        .await
        .unwrap_err();
    assert_eq!(e.code(), Some(ErrorCode::PermissionDenied));
    let e = c
        .create_match(CreateMatch {
            token: BLUE.into(),
            ..Default::default()
        })
        .await
        .unwrap_err();
    assert_eq!(e.code(), Some(ErrorCode::PermissionDenied));
    let info = c
        .create_match(CreateMatch {
            token: ADMIN.into(),
            seed: Some(5),
            minutes: Some(0.5),
            mode: Some(Mode::Realtime),
            ..Default::default()
        })
        .await
        .unwrap();
    assert_eq!(info.match_id, MatchId(2));
    assert_eq!(info.seed, 5);
    assert_eq!(info.total_ticks, 300);
    assert_eq!(info.state, MatchState::Waiting);
    let bad = CreateMatch {
        token: ADMIN.into(),
        minutes: Some(-1.0),
        ..Default::default()
    };
    assert_eq!(
        c.create_match(bad).await.unwrap_err().code(),
        Some(ErrorCode::InvalidArgument)
    );
    let list = c.list_matches().await.unwrap();
    assert_eq!(
        list.iter().map(|m| m.match_id.0).collect::<Vec<_>>(),
        [1, 2]
    );
    let e = c
        .join(Some(MatchId(9)), Team::Blue, BLUE, &[p(0)])
        .await
        .unwrap_err();
    assert_eq!(e.code(), Some(ErrorCode::NotFound));
    assert_eq!(c.ping(1).await.unwrap(), 1);
    server.stop().await;
}

#[tokio::test]
async fn taken_slots_and_acting_for_others_are_refused() {
    let server = start(config(10)).await;
    let addr = server.addr();
    let mut a = Client::connect(addr.as_str(), "a").await.unwrap();
    let joined = a
        .join(Some(MatchId(1)), Team::Blue, BLUE, &[p(0), p(1)])
        .await
        .unwrap();
    assert_eq!(joined.players, [p(0), p(1)]);
    let list = a.list_matches().await.unwrap();
    assert_eq!(list[0].taken.blue, [true, true, false, false]);

    let mut b = Client::connect(addr.as_str(), "b").await.unwrap();
    let e = b
        .join(Some(MatchId(1)), Team::Blue, BLUE, &[p(1), p(2)])
        .await
        .unwrap_err();
    assert_eq!(e.code(), Some(ErrorCode::FailedPrecondition));
    let e = b
        .join(Some(MatchId(1)), Team::Blue, BLUE, &[p(2), p(2)])
        .await
        .unwrap_err();
    assert_eq!(e.code(), Some(ErrorCode::InvalidArgument));
    // Without a match id: the oldest match with these slots free (match 1).
    assert_eq!(
        b.join(None, Team::Blue, BLUE, &[p(2)])
            .await
            .unwrap()
            .match_id,
        MatchId(1)
    );
    let e = b.join(None, Team::Red, RED, &[p(0)]).await.unwrap_err();
    assert_eq!(
        e.code(),
        Some(ErrorCode::FailedPrecondition),
        "one match per connection"
    );

    // Acting for the other team, or for a teammate another connection runs.
    let act = |team, player| {
        ClientMsg::Action(ActionMsg {
            tick: 0,
            team,
            actions: vec![PlayerAction {
                player: p(player),
                action: Action::Forward,
            }],
        })
    };
    a.send(&act(Some(Team::Red), 0)).await.unwrap();
    let e = expect_error(&mut a, ErrorCode::PermissionDenied, false).await;
    assert_eq!(e.in_reply_to.as_deref(), Some("action"));
    a.send(&act(None, 2)).await.unwrap();
    expect_error(&mut a, ErrorCode::PermissionDenied, false).await;
    // Own players, but the match has not started (5 of 8 robots missing).
    a.send(&act(Some(Team::Blue), 1)).await.unwrap();
    expect_error(&mut a, ErrorCode::FailedPrecondition, false).await;

    assert_eq!(a.leave().await.unwrap(), MatchId(1));
    let mut c = Client::connect(addr.as_str(), "c").await.unwrap();
    c.join(Some(MatchId(1)), Team::Blue, BLUE, &[p(0), p(1)])
        .await
        .unwrap();
    assert_eq!(
        a.leave().await.unwrap_err().code(),
        Some(ErrorCode::FailedPrecondition)
    );
    server.stop().await;
}

/// A connection that never says hello is closed after the hello timeout
/// (tokio's paused clock jumps there; the server is real).
#[tokio::test(start_paused = true)]
async fn silent_connection_is_closed_after_the_hello_timeout() {
    let server = start(config(10)).await;
    let stream = TcpStream::connect(server.addr).await.unwrap();
    let (mut r, _w) = stream.into_split();
    use tokio::io::AsyncReadExt;
    let mut len = [0u8; 4];
    r.read_exact(&mut len).await.unwrap();
    let mut body = vec![0u8; u32::from_be_bytes(len) as usize];
    r.read_exact(&mut body).await.unwrap();
    let msg: ServerMsg = serde_json::from_slice(&body).unwrap();
    assert!(
        matches!(
            msg,
            ServerMsg::Error(ErrorMsg {
                code: ErrorCode::DeadlineExceeded,
                fatal: true,
                ..
            })
        ),
        "{msg:?}"
    );
    server.stop().await;
}
