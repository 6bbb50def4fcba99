//! Property: whatever bytes a peer sends, the server answers with valid
//! protocol messages (errors, or replies to what parsed) and closes or keeps
//! the connection, never panics; a lockstep match on another connection
//! keeps ticking throughout (issue 6).

use crate::common;

use common::server::*;
use naosoccer_client::{Client, Push};
use naosoccer_proto::msg::{MatchId, Player, PlayerAction, ServerMsg};
use naosoccer_proto::{frame, Action, Team};
use proptest::prelude::*;
use proptest::test_runner::{Config, TestRunner};
use std::time::Duration;
use tokio::io::{AsyncReadExt, AsyncWriteExt};
use tokio::net::TcpStream;
use tokio::sync::watch;

fn framed(payload: &[u8]) -> Vec<u8> {
    let mut v = (payload.len() as u32).to_be_bytes().to_vec();
    v.extend_from_slice(payload);
    v
}

/// Message-shaped JSON with arbitrary values, so parsing gets past `type`.
fn json_msg() -> impl Strategy<Value = Vec<u8>> {
    let word = "[a-z_]{0,12}";
    prop_oneof![
        any::<i64>().prop_map(|n| format!(r#"{{"type":"ping","nonce":{n}}}"#)),
        (word, any::<i32>(), any::<u8>()).prop_map(|(t, m, pl)| format!(
            r#"{{"type":"join","match_id":{m},"team":"{t}","token":"x","players":[{pl}]}}"#
        )),
        (any::<i64>(), any::<u8>(), word).prop_map(|(tick, pl, a)| format!(
            r#"{{"type":"action","tick":{tick},"actions":[{{"player":{pl},"action":"{a}"}}]}}"#
        )),
        (any::<f64>(), any::<u64>()).prop_map(|(min, seed)| format!(
            r#"{{"type":"create_match","token":"guess","minutes":{min},"seed":{seed}}}"#
        )),
        word.prop_map(|t| format!(r#"{{"type":"{t}"}}"#)),
        Just(r#"{"type":"leave"}"#.to_owned()),
        Just(r#"{"type":"list_matches"}"#.to_owned()),
    ]
    .prop_map(String::into_bytes)
}

fn hello() -> Vec<u8> {
    framed(br#"{"type":"hello","protocol":"naosoccer","version":{"major":1,"minor":0}}"#)
}

/// A byte sequence: optionally a valid hello, then pieces that are raw
/// garbage, framed garbage or framed message-shaped JSON.
fn input() -> impl Strategy<Value = Vec<u8>> {
    let piece = prop_oneof![
        proptest::collection::vec(any::<u8>(), 0..48),
        proptest::collection::vec(any::<u8>(), 0..200).prop_map(|p| framed(&p)),
        json_msg().prop_map(|p| framed(&p)),
        json_msg().prop_map(|p| framed(&p)),
    ];
    (any::<bool>(), proptest::collection::vec(piece, 0..6)).prop_map(|(greet, pieces)| {
        let mut v = if greet { hello() } else { Vec::new() };
        for p in pieces {
            v.extend(p);
        }
        v
    })
}

/// Sends `bytes`, half-closes, and reads until the server closes. Every
/// complete frame it sent must be a valid server message.
async fn probe(addr: std::net::SocketAddr, bytes: &[u8]) -> Result<usize, String> {
    let mut s = TcpStream::connect(addr).await.map_err(|e| e.to_string())?;
    // The server may close first (a fatal error); a failed write is fine.
    let _ = s.write_all(bytes).await;
    let _ = s.shutdown().await;
    let mut got = Vec::new();
    let read = tokio::time::timeout(Duration::from_secs(20), s.read_to_end(&mut got)).await;
    // Ok(Err(_)), a reset after a fatal error, is a closed connection too.
    if read.is_err() {
        return Err("the server neither answered nor closed in 20 s".into());
    }
    let dec = frame::FrameDecoder::new(usize::MAX >> 1);
    let mut at = 0;
    let mut msgs = 0;
    while let Some(span) = dec.decode(&got[at..]).map_err(|e| e.to_string())? {
        let payload = &got[at + span.start..at + span.end];
        let msg: ServerMsg = serde_json::from_slice(payload)
            .map_err(|e| format!("invalid server message {e}: {payload:?}"))?;
        if matches!(msg, ServerMsg::Unknown) {
            return Err("server sent an unknown message type".into());
        }
        msgs += 1;
        at += span.end;
    }
    Ok(msgs)
}

#[test]
fn arbitrary_bytes_get_errors_or_a_close_while_a_match_ticks() {
    let rt = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()
        .unwrap();
    let mut cfg = config(1_000_000);
    cfg.start_players = 4;
    cfg.deadline_ms = 60_000;
    let (server, ticks, player) = rt.block_on(async {
        let server = start(cfg).await;
        let (tx, rx) = watch::channel(0u64);
        let mut c = Client::connect(server.addr(), "ticker").await.unwrap();
        let players: Vec<Player> = Player::all().collect();
        c.join(Some(MatchId(1)), Team::Blue, BLUE, &players)
            .await
            .unwrap();
        let player = tokio::spawn(async move {
            let actions: Vec<PlayerAction> = players
                .iter()
                .map(|&player| PlayerAction {
                    player,
                    action: Action::Stay,
                })
                .collect();
            loop {
                match c.next_push().await {
                    Ok(Push::Observation(o)) => {
                        let _ = tx.send(o.tick.get());
                        c.send_actions(o.tick, &actions).await.unwrap();
                    }
                    Ok(Push::MatchEnd(end)) => return end,
                    other => panic!("the ticking match was disturbed: {other:?}"),
                }
            }
        });
        (server, rx, player)
    });
    let addr = server.addr;
    let mut runner = TestRunner::new(Config {
        cases: 128,
        failure_persistence: None,
        ..Config::default()
    });
    let mut ticks = ticks;
    let before = *ticks.borrow();
    let replies = std::cell::Cell::new(0usize);
    runner
        .run(&input(), |bytes| {
            let r = rt.block_on(probe(addr, &bytes));
            prop_assert!(r.is_ok(), "{:?}", r);
            replies.set(replies.get() + r.unwrap_or(0));
            Ok(())
        })
        .unwrap();
    assert!(
        replies.get() > 128,
        "the server answered only {} messages",
        replies.get()
    );
    rt.block_on(async {
        // Still ticking: a hundred more ticks arrive after the run.
        let now = *ticks.borrow();
        assert!(now > before, "the match did not tick during the run");
        tokio::time::timeout(Duration::from_secs(60), ticks.wait_for(|t| *t >= now + 100))
            .await
            .expect("the match stopped ticking")
            .unwrap();
        let mut c = Client::connect(server.addr(), "probe").await.unwrap();
        assert_eq!(c.ping(5).await.unwrap(), 5);
        server.stop().await;
        let end = player.await.unwrap();
        assert_eq!(end.reason, naosoccer_proto::msg::EndReason::Shutdown);
    });
}
