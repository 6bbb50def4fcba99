//! `--live`: a real viewer over a real WebSocket. The test speaks the
//! Foxglove SDK's WebSocket protocol (`foxglove.sdk.v1`: JSON control
//! messages, binary message data) to the real binary on an ephemeral
//! loopback port.

use std::io::{BufRead, BufReader};
use std::process::{Child, Command, Stdio};
use std::time::Duration;

use futures_util::{SinkExt, StreamExt};
use serde_json::{json, Value};
use tokio::net::TcpStream;
use tokio_tungstenite::tungstenite::client::IntoClientRequest;
use tokio_tungstenite::tungstenite::Message;
use tokio_tungstenite::WebSocketStream;

type Ws = WebSocketStream<TcpStream>;

fn naosoccer() -> Command {
    Command::new(env!("CARGO_BIN_EXE_naosoccer"))
}

/// Starts `naosoccer ARGS` and reads its stderr up to the `live: ws://ADDR`
/// line; the rest of stderr is drained on a thread.
fn spawn_live(args: &[&str]) -> (Child, String) {
    let mut child = naosoccer()
        .args(args)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("run naosoccer");
    let mut err = BufReader::new(child.stderr.take().unwrap());
    let mut line = String::new();
    let addr = loop {
        line.clear();
        assert!(
            err.read_line(&mut line).unwrap() > 0,
            "naosoccer ended before announcing its live address"
        );
        if let Some(rest) = line.trim().strip_prefix("live: ws://") {
            break rest.split_whitespace().next().unwrap().to_string();
        }
    };
    std::thread::spawn(move || std::io::copy(&mut err, &mut std::io::sink()));
    (child, addr)
}

async fn connect(addr: &str) -> Ws {
    let mut req = format!("ws://{addr}").into_client_request().unwrap();
    req.headers_mut()
        .insert("sec-websocket-protocol", "foxglove.sdk.v1".parse().unwrap());
    let tcp = TcpStream::connect(addr).await.unwrap();
    let (ws, resp) = tokio_tungstenite::client_async(req, tcp).await.unwrap();
    assert_eq!(
        resp.headers()["sec-websocket-protocol"],
        "foxglove.sdk.v1",
        "the server speaks the Foxglove SDK subprotocol"
    );
    ws
}

/// Reads control messages until every topic in `want` is advertised;
/// returns the advertised channels by topic.
async fn advertised(ws: &mut Ws, want: &[&str]) -> std::collections::BTreeMap<String, Value> {
    // A match's channels are created one after the other, and the SDK may
    // advertise one a moment before it takes subscriptions for it: wait for
    // the whole set (the log channel is created last).
    let all = ["scene", "tf", "state", "score", "events", "stats", "log"]
        .map(|t| format!("/match/1/{t}"));
    let mut channels = std::collections::BTreeMap::new();
    while !want.iter().all(|t| channels.contains_key(*t))
        || !all.iter().all(|t| channels.contains_key(t))
    {
        let msg = ws.next().await.expect("open").expect("a message");
        if let Message::Text(t) = msg {
            let v: Value = serde_json::from_str(&t).unwrap();
            if v["op"] == "advertise" {
                for c in v["channels"].as_array().unwrap() {
                    channels.insert(c["topic"].as_str().unwrap().to_string(), c.clone());
                }
            }
        }
    }
    channels
}

async fn subscribe(ws: &mut Ws, channels: &[(u32, &Value)]) {
    let subs: Vec<Value> = channels
        .iter()
        .map(|(sub, c)| json!({"id": sub, "channelId": c["id"]}))
        .collect();
    let msg = json!({"op": "subscribe", "subscriptions": subs});
    ws.send(Message::Text(msg.to_string().into()))
        .await
        .unwrap();
}

/// The next message data frame: (subscription id, payload as JSON).
async fn next_data(ws: &mut Ws) -> Option<(u32, Value)> {
    loop {
        match ws.next().await? {
            Ok(Message::Binary(b)) => {
                assert_eq!(b[0], 1, "opcode 1: message data");
                let sub = u32::from_le_bytes(b[1..5].try_into().unwrap());
                let v = serde_json::from_slice(&b[13..]).expect("JSON payload");
                return Some((sub, v));
            }
            Ok(_) => continue,
            Err(_) => return None,
        }
    }
}

fn final_hash(child: Child) -> String {
    let out = child.wait_with_output().unwrap();
    assert!(out.status.success());
    let v: Value = serde_json::from_slice(&out.stdout).expect("--json output");
    v["state_hash"].as_str().unwrap().to_string()
}

fn unwatched_hash(args: &[&str]) -> String {
    let out = naosoccer().args(args).output().unwrap();
    assert!(out.status.success());
    let v: Value = serde_json::from_slice(&out.stdout).unwrap();
    v["state_hash"].as_str().unwrap().to_string()
}

/// A viewer sees the scene advertised as foxglove.SceneUpdate, subscribes,
/// and gets scenes with 8 robots and a ball and every tick's state in order;
/// the match ends with the hash it has unwatched.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn match_live_streams_the_scene_and_changes_nothing() {
    let base = ["match", "--seed", "5", "--minutes", "0.5", "--json"];
    let mut args = base.to_vec();
    args.extend(["--live", "127.0.0.1:0", "--speed", "10", "--wait-viewer"]);
    let (child, addr) = spawn_live(&args);
    let mut ws = connect(&addr).await;
    let ch = advertised(
        &mut ws,
        &["/match/1/scene", "/match/1/state", "/match/1/tf"],
    )
    .await;
    let scene = &ch["/match/1/scene"];
    assert_eq!(scene["schemaName"], "foxglove.SceneUpdate");
    assert_eq!(scene["encoding"], "json");
    assert_eq!(ch["/match/1/tf"]["schemaName"], "foxglove.FrameTransforms");
    subscribe(&mut ws, &[(1, scene), (2, &ch["/match/1/state"])]).await;

    let (mut scenes, mut pitches, mut ticks) = (0, 0, Vec::new());
    while let Some((sub, v)) = next_data(&mut ws).await {
        // Scenes come before the state of the same tick.
        if sub == 1 {
            let ids: Vec<&str> = v["entities"]
                .as_array()
                .unwrap()
                .iter()
                .map(|e| e["id"].as_str().unwrap())
                .collect();
            let robots = ids.iter().filter(|i| i.starts_with("robot_")).count();
            assert_eq!(robots, 8, "{ids:?}");
            assert!(
                ids.contains(&"ball") && ids.contains(&"scoreboard"),
                "{ids:?}"
            );
            pitches += ids.contains(&"pitch") as u32;
            scenes += 1;
        } else {
            ticks.push(v["tick"].as_u64().unwrap());
            assert_eq!(v["robots"].as_array().unwrap().len(), 8);
            if ticks.last() == Some(&300) {
                break;
            }
        }
    }
    // The server keeps serving until its viewers leave (or 5 s pass).
    ws.close(None).await.unwrap();
    // Kick-off and 300 ticks, every one in order; the pitch once a second.
    assert_eq!(ticks, (0..=300).collect::<Vec<_>>());
    assert_eq!(scenes, 301);
    assert_eq!(pitches, 31);
    assert_eq!(final_hash(child), unwatched_hash(&base));
}

/// A viewer that subscribes to everything and then stops reading neither
/// slows the match to a halt nor changes it: the SDK drops its oldest
/// queued messages.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_stalled_viewer_changes_nothing() {
    // 2 game minutes as fast as the stream goes: ~20 MB of scenes, more than
    // the socket buffers hold for a viewer that reads nothing.
    let base = ["match", "--seed", "6", "--minutes", "2", "--json"];
    let mut args = base.to_vec();
    args.extend(["--live", "127.0.0.1:0", "--speed", "10000", "--wait-viewer"]);
    let (child, addr) = spawn_live(&args);
    let mut ws = connect(&addr).await;
    let ch = advertised(&mut ws, &["/match/1/scene"]).await;
    let all: Vec<(u32, &Value)> = ch.values().zip(1..).map(|(c, i)| (i, c)).collect();
    subscribe(&mut ws, &all).await;
    // Stop reading; the match must still end by itself.
    let hash = tokio::task::spawn_blocking(move || final_hash(child));
    let hash = tokio::time::timeout(Duration::from_secs(120), hash)
        .await
        .expect("the match ends although its viewer stalls")
        .unwrap();
    assert_eq!(hash, unwatched_hash(&base));
    drop(ws);
}

/// `replay --live` streams every recorded tick in order, with the recorded
/// events, then checks the recording as a plain `replay` does.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn replay_live_streams_every_tick_in_order() {
    let dir = std::env::temp_dir().join(format!("naosoccer-live-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("r.mcap");
    let f = file.to_str().unwrap();
    let out = naosoccer()
        .args(["match", "--seed", "4", "--minutes", "0.3", "--record", f])
        .output()
        .unwrap();
    assert!(out.status.success());
    let summary = naosoccer()
        .args(["replay", f, "--summary"])
        .output()
        .unwrap();
    let summary = String::from_utf8_lossy(&summary.stdout).to_string();
    let recorded_events: usize = summary
        .lines()
        .find_map(|l| l.strip_suffix(" goals)").and_then(|l| l.split(' ').next()))
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("event count in {summary}"));

    let args = [
        "replay",
        f,
        "--live",
        "127.0.0.1:0",
        "--speed",
        "20",
        "--wait-viewer",
    ];
    let (child, addr) = spawn_live(&args);
    let mut ws = connect(&addr).await;
    let ch = advertised(
        &mut ws,
        &[
            "/match/1/scene",
            "/match/1/state",
            "/match/1/events",
            "/match/1/log",
        ],
    )
    .await;
    assert_eq!(ch["/match/1/log"]["schemaName"], "foxglove.Log");
    subscribe(
        &mut ws,
        &[
            (1, &ch["/match/1/scene"]),
            (2, &ch["/match/1/state"]),
            (3, &ch["/match/1/events"]),
            (4, &ch["/match/1/log"]),
        ],
    )
    .await;
    let (mut ticks, mut events, mut scenes, mut logs) = (Vec::new(), 0, 0, 0);
    while let Some((sub, v)) = next_data(&mut ws).await {
        match sub {
            1 => scenes += 1,
            2 => {
                ticks.push(v["tick"].as_u64().unwrap());
                if ticks.last() == Some(&180) {
                    break;
                }
            }
            3 => {
                assert!(v["kind"].is_string(), "{v}");
                events += 1;
            }
            _ => {
                assert!(v["message"].as_str().unwrap().contains("\"kind\""), "{v}");
                logs += 1;
            }
        }
    }
    ws.close(None).await.unwrap();
    assert_eq!(ticks, (0..=180).collect::<Vec<_>>());
    assert_eq!(scenes, 181);
    assert_eq!(events, recorded_events);
    assert_eq!(logs, recorded_events);
    let out = child.wait_with_output().unwrap();
    assert_eq!(out.status.code(), Some(0));
    assert_eq!(
        String::from_utf8_lossy(&out.stdout).trim(),
        "identical (180 ticks)"
    );
}

/// `server --live`: a viewer of a running real-time server match gets its
/// scene ten times a game second, every tick in order, and the match's
/// recording is byte for byte the one an unwatched server writes.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn server_live_streams_a_running_match_and_changes_nothing() {
    let root = std::env::temp_dir().join(format!("naosoccer-live-server-{}", std::process::id()));
    let (watched, unwatched) = (root.join("watched"), root.join("unwatched"));
    let server = |dir: &std::path::Path| {
        vec![
            "server".to_string(),
            "--port".into(),
            "0".into(),
            "--start-players".into(),
            "0".into(),
            "--mode".into(),
            "realtime".into(),
            "--minutes".into(),
            "0.1".into(),
            "--exit-when-done".into(),
            "--record-dir".into(),
            dir.to_str().unwrap().into(),
        ]
    };
    let plain = naosoccer()
        .args(server(&unwatched))
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let mut args = server(&watched);
    args.extend(["--live".into(), "127.0.0.1:0".into()]);
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    let (child, addr) = spawn_live(&args);
    let mut ws = connect(&addr).await;
    let ch = advertised(&mut ws, &["/match/1/scene", "/match/1/state"]).await;
    assert_eq!(ch["/match/1/scene"]["schemaName"], "foxglove.SceneUpdate");
    subscribe(
        &mut ws,
        &[(1, &ch["/match/1/scene"]), (2, &ch["/match/1/state"])],
    )
    .await;
    let (mut scenes, mut ticks) = (0, Vec::<u64>::new());
    while let Some((sub, v)) = next_data(&mut ws).await {
        if sub == 1 {
            let e = v["entities"].as_array().unwrap();
            let robots = e
                .iter()
                .filter(|e| e["id"].as_str().unwrap().starts_with("robot_"));
            assert_eq!(robots.count(), 8);
            assert!(e.iter().any(|e| e["id"] == "ball"));
            scenes += 1;
        } else {
            ticks.push(v["tick"].as_u64().unwrap());
            if ticks.last() == Some(&60) {
                break;
            }
        }
    }
    // The viewer came in after the start, but saw most of the 60 ticks, in
    // order, up to the last (the server sends at most 30 ticks per second,
    // so a burst of late real-time ticks may be thinned).
    assert!(scenes >= 30, "{scenes} scenes");
    assert!(
        ticks.len() >= 30,
        "{scenes} scenes, states of ticks {ticks:?}; channels {ch:?}"
    );
    assert!(ticks.windows(2).all(|w| w[0] < w[1]), "{ticks:?}");
    assert_eq!(ticks.last(), Some(&60));
    drop(ws);
    let out = child.wait_with_output().unwrap();
    assert!(out.status.success());
    assert!(plain.wait_with_output().unwrap().status.success());
    let file = "match-1-seed-1.mcap";
    assert_eq!(
        std::fs::read(watched.join(file)).unwrap(),
        std::fs::read(unwatched.join(file)).unwrap(),
        "a viewer changed the recording"
    );
}
