//! Misbehaving clients get the documented error, and the server keeps
//! serving everyone else.

use crate::common;

use common::server::*;
use naosoccer_client::{Client, ClientError};
use naosoccer_proto::frame;
use naosoccer_proto::msg::{
    ActionMsg, ClientMsg, CreateMatch, ErrorCode, ErrorMsg, Hello, MatchId, MatchState, Mode,
    Player, PlayerAction, ServerMsg, Version,
};
use naosoccer_proto::{Action, Team, Tick};
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
    // The error names the request's type when the frame is a JSON object
    // with a string `type` (issue 15).
    for (bad, in_reply_to) in [
        (&b"{\"type\": \"ping\","[..], None),
        (b"[1,2,3]", None),
        (b"{\"nonce\": 3}", None),
        (b"\xff\xfe", None),
        (b"{\"type\":\"join\",\"team\":\"green\"}", Some("join")),
    ] {
        let mut f = (bad.len() as u32).to_be_bytes().to_vec();
        f.extend_from_slice(bad);
        c.send_raw(&f).await.unwrap();
        let e = expect_error(&mut c, ErrorCode::InvalidArgument, false).await;
        assert_eq!(e.in_reply_to.as_deref(), in_reply_to, "{e:?}");
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
            tick: Tick::ZERO,
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

/// What a client that pairs replies as docs/PROTOCOL.md section 2 says sees:
/// observations, `match_end` and errors with `"in_reply_to": "action"` are
/// pushes; anything else answers the oldest request still waiting, and an
/// error names that request's `type`. Each message is described in a word
/// or two so a whole conversation compares at once.
fn pair(waiting: &mut std::collections::VecDeque<&'static str>, msg: &ServerMsg) -> String {
    let push = match msg {
        ServerMsg::Observation(o) => return format!("push observation {}", o.tick),
        ServerMsg::MatchEnd(_) => return "push match_end".into(),
        ServerMsg::Error(e) => e.in_reply_to.as_deref() == Some("action"),
        _ => false,
    };
    if push {
        let ServerMsg::Error(e) = msg else {
            unreachable!()
        };
        return format!("push action error {} tick {:?}", e.code, e.tick);
    }
    let Some(request) = waiting.pop_front() else {
        panic!("a reply with no request waiting: {msg:?}");
    };
    match msg {
        ServerMsg::Error(e) => {
            assert_eq!(
                e.in_reply_to.as_deref(),
                Some(request),
                "an error answering {request} must say so: {e:?}"
            );
            format!("{request}: {}", e.code)
        }
        ServerMsg::Pong(p) => format!("{request}: pong {}", p.nonce),
        other => format!("{request}: {other:?}"),
    }
}

fn raw(json: &str) -> Vec<u8> {
    let mut f = (json.len() as u32).to_be_bytes().to_vec();
    f.extend_from_slice(json.as_bytes());
    f
}

/// Issue 15 A.1: a request whose `type` is known but a field fails to decode
/// is answered with an error that names its type (and an action's tick), so
/// a bad action followed by a `ping` gets the error and then the `pong`,
/// each pairable; in the lobby and in a running match alike.
#[tokio::test]
async fn errors_for_undecodable_fields_are_pairable() {
    let mut cfg = config(100);
    cfg.start_players = 1;
    // No tick passes on its own while the test talks: the match waits.
    cfg.deadline_ms = 600_000;
    let server = start(cfg).await;

    // In the lobby: a bad action is a push, the ping's pong the reply.
    let mut lobby = Client::connect(server.addr().as_str(), "lobby")
        .await
        .unwrap();
    let mut bytes = raw(r#"{"type":"action","tick":5,"actions":[{"player":0,"action":"dance"}]}"#);
    bytes.extend(raw(r#"{"type":"ping","nonce":8}"#));
    lobby.send_raw(&bytes).await.unwrap();
    let mut waiting = std::collections::VecDeque::from(["ping"]);
    let mut seen = Vec::new();
    for _ in 0..2 {
        seen.push(pair(&mut waiting, &lobby.recv().await.unwrap()));
    }
    assert_eq!(
        seen,
        [
            "push action error invalid_argument tick Some(5)",
            "ping: pong 8"
        ]
    );

    // In a match, waiting on this client's action for tick 0.
    let mut c = Client::connect(server.addr().as_str(), "pairing")
        .await
        .unwrap();
    c.join(Some(MatchId(1)), Team::Blue, BLUE, &[p(0)])
        .await
        .unwrap();
    assert!(matches!(c.recv().await.unwrap(), ServerMsg::Observation(o) if o.tick == Tick::ZERO));
    // (frame, the request type it makes, if it is a request)
    let frames: [(&str, Option<&'static str>); 11] = [
        (
            r#"{"type":"action","tick":0,"actions":[{"player":0,"action":"dance"}]}"#,
            None,
        ),
        (r#"{"type":"ping","nonce":1}"#, Some("ping")),
        (
            r#"{"type":"action","tick":0,"actions":[{"player":9,"action":"stay"}]}"#,
            None,
        ),
        (r#"{"type":"ping","nonce":2}"#, Some("ping")),
        (
            r#"{"type":"action","tick":0,"team":"green","actions":[]}"#,
            None,
        ),
        (
            r#"{"type":"create_match","token":"admin-secret","mode":"fast"}"#,
            Some("create_match"),
        ),
        (r#"{"type":"ping","nonce":"17"}"#, Some("ping")),
        (
            r#"{"type":"join","match_id":1,"team":"green","token":"x","players":[1]}"#,
            Some("join"),
        ),
        (r#"{"type":"action","tick":"zero","actions":[]}"#, None),
        (r#"[1,2,3]"#, Some("(not an object)")),
        (r#"{"type":"ping","nonce":3}"#, Some("ping")),
    ];
    let mut bytes = Vec::new();
    let mut waiting = std::collections::VecDeque::new();
    for (json, request) in frames {
        bytes.extend(raw(json));
        waiting.extend(request);
    }
    c.send_raw(&bytes).await.unwrap();
    let mut seen = Vec::new();
    for _ in 0..frames.len() {
        let msg = c.recv().await.unwrap();
        // An error for a frame that is not an object cannot name a type: it
        // answers in order (the pairing rule still holds).
        if waiting.front() == Some(&"(not an object)") {
            if let ServerMsg::Error(e) = &msg {
                if e.in_reply_to.is_none() {
                    waiting.pop_front();
                    seen.push(format!("(not an object): {}", e.code));
                    continue;
                }
            }
        }
        seen.push(pair(&mut waiting, &msg));
    }
    assert_eq!(
        seen,
        [
            "push action error invalid_argument tick Some(0)",
            "ping: pong 1",
            "push action error invalid_argument tick Some(0)",
            "ping: pong 2",
            "push action error invalid_argument tick Some(0)",
            "create_match: invalid_argument",
            "ping: invalid_argument",
            "join: invalid_argument",
            "push action error invalid_argument tick None",
            "(not an object): invalid_argument",
            "ping: pong 3",
        ]
    );
    assert!(waiting.is_empty());
    // The match still waits on this robot, and plays on once it answers.
    c.send_actions(
        Tick::ZERO,
        &[PlayerAction {
            player: p(0),
            action: Action::Stay,
        }],
    )
    .await
    .unwrap();
    assert!(matches!(c.recv().await.unwrap(), ServerMsg::Observation(o) if o.tick == Tick::new(1)));
    assert_eq!(c.ping(4).await.unwrap(), 4);
    server.stop().await;
}

/// Issue 39: a frame nested far deeper than serde_json parses (30,000
/// levels, within the frame cap) is refused as `invalid_argument`, and the
/// error still names its `type` (and an action's `tick`): every frame that
/// is a JSON object with a string `type` gets `in_reply_to`. A payload that
/// deep but not valid JSON, or without a `type`, still gets none.
#[tokio::test]
async fn issue_39_an_error_for_a_frame_nested_30000_deep_names_its_type() {
    let server = start(config(10)).await;
    let mut c = Client::connect(server.addr().as_str(), "deep")
        .await
        .unwrap();
    let deep = |head: &str, cut: usize| {
        format!(
            r#"{{{head}"x":{}{}}}"#,
            "[".repeat(30_000),
            "]".repeat(30_000 - cut)
        )
    };
    let cases = [
        (
            deep(r#""type":"create_match","#, 0),
            Some("create_match"),
            None,
        ),
        (
            deep(r#""type":"action","tick":3,"#, 0),
            Some("action"),
            Some(3),
        ),
        (deep(r#""type":"teleport","#, 0), Some("unknown"), None),
        (deep(r#""type":"ping","#, 1), None, None),
        (deep("", 0), None, None),
    ];
    for (json, kind, tick) in &cases {
        assert!(json.len() < 65_536);
        c.send_raw(&raw(json)).await.unwrap();
        let e = expect_error(&mut c, ErrorCode::InvalidArgument, false).await;
        assert_eq!(e.in_reply_to.as_deref(), *kind, "{}", &json[..40]);
        assert_eq!(e.tick, tick.map(Tick::new), "{}", &json[..40]);
    }
    assert_eq!(c.ping(7).await.unwrap(), 7);
    server.stop().await;
}

/// Issue 39: the ranges of `seed`, `deadline_ms`, `match_id` and `nonce`
/// are what docs/PROTOCOL.md says: unsigned 64-bit integers written without
/// fraction or exponent (`deadline_ms` in 1..=600000), `null` for an
/// optional field is leaving it out, everything else `invalid_argument`
/// naming the request.
#[tokio::test]
async fn issue_39_integer_fields_accept_and_refuse_as_documented() {
    let mut cfg = config(10);
    cfg.start_players = 8; // the matches created here only wait
    let server = start(cfg).await;
    let mut c = Client::connect(server.addr().as_str(), "ranges")
        .await
        .unwrap();
    // Sends one request and reads its reply, as the doc's pairing says.
    async fn ask(c: &mut Client, json: &str) -> ServerMsg {
        c.send_raw(&raw(json)).await.unwrap();
        c.recv().await.unwrap()
    }
    let refused = |msg: ServerMsg, request: &str, code: ErrorCode| match msg {
        ServerMsg::Error(e) => {
            assert_eq!(e.code, code, "{e}");
            assert!(!e.fatal, "{e}");
            assert_eq!(e.in_reply_to.as_deref(), Some(request), "{e}");
        }
        other => panic!("{request} should be refused with {code}: {other:?}"),
    };
    const MAX: &str = "18446744073709551615";
    const OVER: &str = "18446744073709551616";
    let bad_integers = ["-1", "-0", "1.0", "1e2", OVER, r#""1""#];

    // ping's nonce: any u64, echoed; null is not "left out".
    for nonce in ["0", "17", MAX] {
        let json = format!(r#"{{"type":"ping","nonce":{nonce}}}"#);
        match ask(&mut c, &json).await {
            ServerMsg::Pong(p) => assert_eq!(p.nonce.to_string(), nonce),
            other => panic!("{json}: {other:?}"),
        }
    }
    for nonce in bad_integers.iter().chain(&["null"]) {
        let json = format!(r#"{{"type":"ping","nonce":{nonce}}}"#);
        refused(ask(&mut c, &json).await, "ping", ErrorCode::InvalidArgument);
    }

    // create_match's seed and deadline_ms.
    let create = |field: &str, value: &str| {
        format!(r#"{{"type":"create_match","token":"{ADMIN}","{field}":{value}}}"#)
    };
    let created = |msg: ServerMsg| match msg {
        ServerMsg::MatchCreated(m) => m.info,
        other => panic!("not created: {other:?}"),
    };
    for seed in ["0", MAX] {
        let info = created(ask(&mut c, &create("seed", seed)).await);
        assert_eq!(info.seed.to_string(), seed);
    }
    // null: the default, server seed + match id - 1.
    let info = created(ask(&mut c, &create("seed", "null")).await);
    assert_eq!(info.seed, 42 + info.match_id.0 - 1);
    for seed in bad_integers {
        let reply = ask(&mut c, &create("seed", seed)).await;
        refused(reply, "create_match", ErrorCode::InvalidArgument);
    }
    for ms in ["1", "600000"] {
        let info = created(ask(&mut c, &create("deadline_ms", ms)).await);
        assert_eq!(info.deadline_ms.to_string(), ms);
    }
    for ms in bad_integers.iter().chain(&["0", "600001", MAX]) {
        let reply = ask(&mut c, &create("deadline_ms", ms)).await;
        refused(reply, "create_match", ErrorCode::InvalidArgument);
    }
    let listed: Vec<u64> = c
        .list_matches()
        .await
        .unwrap()
        .iter()
        .map(|m| m.match_id.0)
        .collect();
    assert_eq!(listed, [1, 2, 3, 4, 5, 6], "refused requests made no match");

    // match_id: a u64 that names no match is not_found, 0 included.
    for id in ["0", "7", MAX] {
        let join = format!(
            r#"{{"type":"join","match_id":{id},"team":"blue","token":"{BLUE}","players":[0]}}"#
        );
        refused(ask(&mut c, &join).await, "join", ErrorCode::NotFound);
        let end = format!(r#"{{"type":"end_match","token":"{ADMIN}","match_id":{id}}}"#);
        refused(ask(&mut c, &end).await, "end_match", ErrorCode::NotFound);
    }
    for id in bad_integers.iter().chain(&["null"]) {
        let end = format!(r#"{{"type":"end_match","token":"{ADMIN}","match_id":{id}}}"#);
        refused(
            ask(&mut c, &end).await,
            "end_match",
            ErrorCode::InvalidArgument,
        );
    }
    for id in bad_integers {
        let join = format!(
            r#"{{"type":"join","match_id":{id},"team":"blue","token":"{BLUE}","players":[0]}}"#
        );
        refused(ask(&mut c, &join).await, "join", ErrorCode::InvalidArgument);
    }
    // null: no match named, the oldest unfinished one with the slot free.
    let join = format!(
        r#"{{"type":"join","match_id":null,"team":"blue","token":"{BLUE}","players":[0]}}"#
    );
    match ask(&mut c, &join).await {
        ServerMsg::Joined(j) => assert_eq!(j.match_id, MatchId(1)),
        other => panic!("{other:?}"),
    }
    server.stop().await;
}
