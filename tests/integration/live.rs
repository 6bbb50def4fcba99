//! `--live`: a real viewer over a real WebSocket. The viewer
//! (`naosoccer::live::viewer`, which `bench server --viewer` uses too)
//! speaks the Foxglove SDK's WebSocket protocol (`foxglove.sdk.v1`: JSON
//! control messages, binary message data) to the real binary on an
//! ephemeral loopback port, and decodes the Foxglove channels' protobuf
//! with the SDK's types.

use std::io::{BufRead, BufReader};
use std::process::{Child, Output, Stdio};
use std::time::Duration;

use naosoccer::live::viewer::{scene_contents, SceneContents, Viewer};
use serde_json::Value;

use crate::common;

use common::naosoccer_cmd as naosoccer;

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

/// A viewer of match 1 (it speaks the SDK's subprotocol, or this fails)
/// and the match's channels once all are advertised, by topic.
async fn watch(addr: &str) -> (Viewer, std::collections::BTreeMap<String, Value>) {
    let mut v = Viewer::connect(addr).await.unwrap();
    let ch = v.advertised(1).await.unwrap();
    (v, ch)
}

/// The final state hash a successful `match --json` run printed.
fn state_hash(out: Output) -> String {
    assert!(out.status.success());
    let v: Value = serde_json::from_slice(&out.stdout).expect("--json output");
    v["state_hash"].as_str().unwrap().to_string()
}

fn unwatched_hash(args: &[&str]) -> String {
    state_hash(naosoccer().args(args).output().unwrap())
}

/// A scene with the whole pitch's players: 8 robots and the ball.
fn assert_full_scene(v: &Value) -> SceneContents {
    let c = scene_contents(v);
    assert_eq!(c.robots, 8, "{v}");
    assert!(c.ball && c.scoreboard, "{v}");
    c
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
    let (mut ws, ch) = watch(&addr).await;
    let scene = &ch["/match/1/scene"];
    assert_eq!(scene["schemaName"], "foxglove.SceneUpdate");
    // The SDK's types: protobuf under the SDK's descriptors.
    assert_eq!(scene["encoding"], "protobuf");
    assert_eq!(scene["schemaEncoding"], "protobuf");
    assert_eq!(ch["/match/1/tf"]["schemaName"], "foxglove.FrameTransforms");
    assert_eq!(ch["/match/1/tf"]["encoding"], "protobuf");
    assert_eq!(ch["/match/1/state"]["encoding"], "json");
    // Every match topic docs/foxglove-layout.json's panels show is one the
    // match advertises (the score panel once named a field it never had).
    let layout: Value = serde_json::from_str(
        &std::fs::read_to_string(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/docs/foxglove-layout.json"
        ))
        .unwrap(),
    )
    .unwrap();
    let mut shown = Vec::new();
    for panel in layout["configById"].as_object().unwrap().values() {
        for key in ["topicPath", "path", "topicToRender"] {
            if let Some(p) = panel[key].as_str() {
                shown.push(p.split('.').next().unwrap().to_string());
            }
        }
        if let Some(rules) = panel.get("rules") {
            assert!(
                !rules.as_array().unwrap().is_empty(),
                "an indicator without rules: {panel}"
            );
        }
    }
    for topic in ["/match/1/score", "/match/1/log", "/match/1/stats"] {
        assert!(
            shown.iter().any(|t| t == topic),
            "the layout does not show {topic}"
        );
    }
    for topic in &shown {
        assert!(
            ch.contains_key(topic),
            "the layout shows {topic}, which is not advertised"
        );
    }
    // The scene last: its subscription releases kick-off (--wait-viewer),
    // and `subscribe` has each taken before it asks for the next.
    ws.subscribe(&[
        (2, &ch["/match/1/state"]),
        (3, &ch["/match/1/tf"]),
        (4, &ch["/match/1/score"]),
        (1, scene),
    ])
    .await
    .unwrap();

    let (mut scenes, mut pitches, mut tfs, mut ticks) = (0, 0, 0, Vec::new());
    let mut scores = 0;
    while let Some((sub, v)) = ws.next_data().await {
        // Scenes and transforms come before the state of the same tick.
        if sub == 1 {
            pitches += assert_full_scene(&v).pitch as u32;
            scenes += 1;
        } else if sub == 4 {
            // The score panel's field: "blue 0 - 0 red   00:00".
            let text = v["text"].as_str().unwrap_or_default();
            assert!(text.starts_with("blue ") && text.contains(" red "), "{v}");
            scores += 1;
        } else if sub == 3 {
            let t = v["transforms"].as_array().unwrap();
            assert_eq!(t.len(), 9, "{v}");
            assert_eq!(t[8]["child_frame_id"], "ball", "{v}");
            tfs += 1;
        } else {
            ticks.push(v["tick"].as_u64().unwrap());
            assert_eq!(v["robots"].as_array().unwrap().len(), 8);
            if ticks.last() == Some(&300) {
                break;
            }
        }
    }
    // The server keeps serving until its viewers leave (or 5 s pass).
    ws.close().await;
    // Kick-off and 300 ticks, every one in order; the pitch once a second.
    assert_eq!(ticks, (0..=300).collect::<Vec<_>>());
    assert_eq!(scenes, 301);
    assert_eq!(tfs, 301);
    assert_eq!(pitches, 31);
    assert!(scores > 0, "no score message");
    assert_eq!(
        state_hash(child.wait_with_output().unwrap()),
        unwatched_hash(&base)
    );
}

/// A match started from a scenario names it on the live scoreboard and in
/// the score messages, and plays the same as unwatched.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn match_live_names_its_scenario() {
    let scenario = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/assets/scenarios/empty-goal.toml"
    );
    let base = ["match", "--scenario", scenario, "--seed", "4", "--json"];
    let mut args = base.to_vec();
    args.extend(["--live", "127.0.0.1:0", "--speed", "100", "--wait-viewer"]);
    let (child, addr) = spawn_live(&args);
    let (mut ws, ch) = watch(&addr).await;
    ws.subscribe(&[(4, &ch["/match/1/score"]), (1, &ch["/match/1/scene"])])
        .await
        .unwrap();
    let mut scores = 0;
    while let Some((sub, v)) = ws.next_data().await {
        if sub != 4 {
            continue;
        }
        let text = v["text"].as_str().unwrap_or_default();
        assert!(
            text.starts_with("empty-goal (blue): blue ") && text.contains(" red "),
            "{v}"
        );
        assert_eq!(v["scenario"]["name"], "empty-goal", "{v}");
        assert_eq!(v["scenario"]["team"], "blue", "{v}");
        scores += 1;
        if scores == 20 {
            break;
        }
    }
    ws.close().await;
    assert_eq!(scores, 20, "the stream ended early");
    assert_eq!(
        state_hash(child.wait_with_output().unwrap()),
        unwatched_hash(&base)
    );
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
    let (mut ws, ch) = watch(&addr).await;
    let all: Vec<(u32, &Value)> = ch.values().zip(1..).map(|(c, i)| (i, c)).collect();
    ws.subscribe(&all).await.unwrap();
    // Stop reading; the match must still end by itself.
    let hash = tokio::task::spawn_blocking(move || state_hash(child.wait_with_output().unwrap()));
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
    let (mut ws, ch) = watch(&addr).await;
    assert_eq!(ch["/match/1/log"]["schemaName"], "foxglove.Log");
    assert_eq!(ch["/match/1/log"]["encoding"], "protobuf");
    // The scene last: its subscription releases the first tick.
    ws.subscribe(&[
        (2, &ch["/match/1/state"]),
        (3, &ch["/match/1/events"]),
        (4, &ch["/match/1/log"]),
        (1, &ch["/match/1/scene"]),
    ])
    .await
    .unwrap();
    let (mut ticks, mut events, mut scenes, mut logs) = (Vec::new(), 0, 0, 0);
    while let Some((sub, v)) = ws.next_data().await {
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
    ws.close().await;
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
    let (mut ws, ch) = watch(&addr).await;
    assert_eq!(ch["/match/1/scene"]["schemaName"], "foxglove.SceneUpdate");
    ws.subscribe(&[(1, &ch["/match/1/scene"]), (2, &ch["/match/1/state"])])
        .await
        .unwrap();
    let (mut scenes, mut ticks) = (0, Vec::<u64>::new());
    while let Some((sub, v)) = ws.next_data().await {
        if sub == 1 {
            assert_full_scene(&v);
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
