//! A client written against protocol 1.1 keeps playing on a 1.2 server
//! (issue 15 B): it knows only the 1.1 messages and fields, ignores fields
//! it does not know and skips message types it does not know, as
//! docs/PROTOCOL.md ("Versioning") requires of every client. It speaks the
//! framing by hand and reads messages into its own 1.1 types, so nothing of
//! this build's protocol crate helps it along.

use crate::common;

use common::server::*;
use naosoccer_policy::PolicyKind;
use serde::Deserialize;
use serde_json::{json, Value};
use tokio::io::{AsyncReadExt, AsyncWriteExt};
use tokio::net::TcpStream;

/// The 1.1 messages the client reads, with their 1.1 fields only (serde
/// ignores the rest, as the client must).
#[derive(Debug, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case")]
enum Msg11 {
    Welcome {
        version: Version11,
    },
    Joined {
        match_id: u64,
        players: Vec<u8>,
        control_hz: f32,
        total_ticks: u64,
    },
    Observation {
        tick: u64,
        observations: Vec<Obs11>,
    },
    MatchEnd {
        reason: String,
        tick: u64,
        score: Score11,
        misses: Misses11,
        rewards: Misses11F,
        state_hash: String,
    },
    Error {
        code: String,
        message: String,
    },
    #[serde(other)]
    Other,
}

#[derive(Debug, Deserialize)]
struct Version11 {
    major: u32,
    minor: u32,
}

#[derive(Debug, Deserialize)]
struct Obs11 {
    tick: u64,
    team: String,
    player: u8,
    time_left: f32,
    own: Vec<Robot11>,
    opponents: Vec<Robot11>,
    ball: Ball11,
    control: Vec<bool>,
    reward: f32,
}

#[derive(Debug, Deserialize)]
struct Robot11 {
    heading: f32,
}

#[derive(Debug, Deserialize)]
struct Ball11 {
    x: f32,
}

#[derive(Debug, Deserialize, PartialEq)]
struct Score11 {
    blue: u32,
    red: u32,
}

#[derive(Debug, Deserialize)]
struct Misses11 {
    blue: Vec<u64>,
}

#[derive(Debug, Deserialize)]
struct Misses11F {
    blue: Vec<f32>,
}

async fn send(s: &mut TcpStream, msg: Value) {
    let payload = serde_json::to_vec(&msg).unwrap();
    s.write_all(&(payload.len() as u32).to_be_bytes())
        .await
        .unwrap();
    s.write_all(&payload).await.unwrap();
}

async fn recv(s: &mut TcpStream) -> (Msg11, Value) {
    let mut len = [0u8; 4];
    s.read_exact(&mut len).await.unwrap();
    let mut payload = vec![0u8; u32::from_be_bytes(len) as usize];
    s.read_exact(&mut payload).await.unwrap();
    let raw: Value = serde_json::from_slice(&payload).unwrap();
    let msg = serde_json::from_slice(&payload)
        .unwrap_or_else(|e| panic!("a 1.1 client cannot read {raw}: {e}"));
    (msg, raw)
}

/// A 1.1 team client plays a whole match on this server: every message it
/// gets reads as 1.1, and the match it plays (standing, against the
/// scripted fill) ends as the same match played in process.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_1_1_client_still_plays() {
    let mut cfg = config(300);
    cfg.deadline_ms = 30_000;
    cfg.start_players = 4;
    let match_cfg = cfg.match_cfg.clone();
    let server = start(cfg).await;
    let mut s = TcpStream::connect(server.addr()).await.unwrap();
    s.set_nodelay(true).unwrap();
    send(
        &mut s,
        json!({"type": "hello", "protocol": "naosoccer", "version": {"major": 1, "minor": 1}, "client": "a 1.1 client"}),
    )
    .await;
    match recv(&mut s).await.0 {
        Msg11::Welcome { version } => assert_eq!(
            (version.major, version.minor),
            (
                naosoccer_proto::msg::PROTOCOL_VERSION.major,
                naosoccer_proto::msg::PROTOCOL_VERSION.minor
            )
        ),
        other => panic!("{other:?}"),
    }
    send(
        &mut s,
        json!({"type": "join", "match_id": 1, "team": "blue", "token": BLUE, "players": [0, 1, 2, 3]}),
    )
    .await;
    let (joined, raw) = recv(&mut s).await;
    match joined {
        Msg11::Joined {
            match_id,
            players,
            control_hz,
            total_ticks,
        } => {
            assert_eq!((match_id, players, total_ticks), (1, vec![0, 1, 2, 3], 300));
            assert_eq!(control_hz, match_cfg.control_hz);
        }
        other => panic!("{other:?}"),
    }
    assert!(raw.get("pitch").is_some(), "1.2 fields are there to ignore");
    let mut ticks = 0u64;
    let mut returns = [0.0f32; 4];
    let mut saw_events = false;
    let end = loop {
        let (msg, raw) = recv(&mut s).await;
        match msg {
            Msg11::Observation { tick, observations } => {
                assert_eq!(tick, ticks);
                assert_eq!(observations.len(), 4);
                for (p, o) in observations.iter().enumerate() {
                    assert_eq!((o.tick, o.player as usize), (tick, p));
                    assert_eq!(o.team, "blue");
                    assert!(o.time_left > 0.0 && o.ball.x.is_finite());
                    assert_eq!((o.own.len(), o.opponents.len(), o.control.len()), (4, 4, 4));
                    assert!(o
                        .own
                        .iter()
                        .chain(&o.opponents)
                        .all(|r| r.heading.abs() <= std::f32::consts::PI));
                    returns[p] += o.reward;
                }
                saw_events |= raw["events"].as_array().is_some_and(|e| !e.is_empty());
                let actions: Vec<Value> = (0..4)
                    .map(|p| json!({"player": p, "action": "stay"}))
                    .collect();
                send(
                    &mut s,
                    json!({"type": "action", "tick": tick, "actions": actions}),
                )
                .await;
                ticks += 1;
            }
            Msg11::MatchEnd {
                reason,
                tick,
                score,
                misses,
                rewards,
                state_hash,
            } => {
                for (r, last) in returns.iter_mut().zip(&rewards.blue) {
                    *r += last;
                }
                assert_eq!(misses.blue, [0; 4]);
                break (reason, tick, score, state_hash);
            }
            Msg11::Error { code, message } => panic!("{code}: {message}"),
            Msg11::Other => {} // a type 1.1 does not know: skipped
            other => panic!("unexpected during the match: {other:?}"),
        }
    };
    assert!(saw_events, "the observations carried 1.2's events");
    let (_stats, score, total, hash) =
        in_process(&match_cfg, 42, PolicyKind::Idle, PolicyKind::Scripted);
    let (reason, tick, got, state_hash) = end;
    assert_eq!(reason, "finished");
    assert_eq!((tick, ticks), (total, total));
    assert_eq!(
        got,
        Score11 {
            blue: score.blue,
            red: score.red
        }
    );
    assert_eq!(state_hash, hash, "the same match as in process");
    assert!(returns.iter().all(|r| r.is_finite()));
    server.stop().await;
}
