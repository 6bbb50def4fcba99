//! Record matches in process and replay them: identical states, repeatable
//! bytes, a tampered action found at its tick, a cut-short file still read.

use std::io::Cursor;

use naosoccer_policy::PolicyKind;
use naosoccer_proto::{Action, RobotId, Team, Tick, ROBOTS};
use naosoccer_record::{
    replay, MatchMeta, Recorder, RecorderOptions, Recording, RecordingSummary, ReplayOutcome,
};
use naosoccer_referee::{blank_observation, Match, MatchConfig};

fn short_config(seconds: f32) -> MatchConfig {
    MatchConfig {
        minutes: seconds / 60.0,
        ..MatchConfig::default()
    }
}

fn meta(cfg: &MatchConfig, seed: u64, m: &Match) -> MatchMeta {
    MatchMeta {
        format: naosoccer_record::RECORDING_FORMAT,
        naosoccer_version: env!("CARGO_PKG_VERSION").into(),
        seed,
        config: cfg.clone(),
        blue: "scripted".into(),
        red: "random".into(),
        source: "match".into(),
        match_id: None,
        mode: None,
        control_hz: cfg.control_hz,
        total_ticks: m.total_ticks(),
        scenario: None,
    }
}

/// Plays a whole match (blue scripted, red random, one policy per robot)
/// and records it in memory.
fn record(cfg: &MatchConfig, seed: u64, opts: RecorderOptions) -> (Vec<u8>, RecordingSummary) {
    let mut m = Match::new(cfg, seed).unwrap();
    let mut policies: Vec<_> = RobotId::all()
        .map(|r| {
            let kind = if r.team() == Team::Blue {
                PolicyKind::Scripted
            } else {
                PolicyKind::Random
            };
            kind.build(seed, r)
        })
        .collect();
    let mut rec = Recorder::in_memory(&meta(cfg, seed, &m), &m, opts).unwrap();
    let mut obs = blank_observation();
    while !m.is_finished() {
        let mut actions = [Action::Stay; ROBOTS];
        for r in RobotId::all() {
            m.observe_into(r.team(), r.player(), &mut obs);
            actions[r.index()] = policies[r.index()].act(&obs);
        }
        let events = m.step(&actions).to_vec();
        rec.tick(&m, &actions, &events).unwrap();
    }
    let (summary, sink) = rec.finish(&m).unwrap();
    (sink.into_bytes().expect("recorded in memory"), summary)
}

#[test]
fn recorded_match_replays_identically_and_counts_match() {
    let cfg = short_config(30.0);
    let (bytes, summary) = record(&cfg, 7, RecorderOptions::default());
    let rec = Recording::read(&bytes).unwrap();
    assert!(rec.truncated.is_none(), "{:?}", rec.truncated);
    assert!(rec.is_complete());
    assert_eq!(rec.actions.len() as u64, 300);
    assert_eq!(rec.states.len(), 301, "tick 0 plus one per tick");
    for (topic, n) in &summary.messages {
        assert_eq!(rec.counts.get(topic).copied().unwrap_or(0), *n, "{topic}");
    }
    assert_eq!(rec.meta.seed, 7);
    assert_eq!(rec.meta.config, cfg);
    match replay(&rec).unwrap() {
        ReplayOutcome::Identical { ticks, truncated } => {
            assert_eq!(ticks, 300);
            assert!(!truncated);
        }
        other => panic!("replay diverged: {other:?}"),
    }
    let stats = rec.stats.as_ref().unwrap();
    assert_eq!(stats.ticks, 300);
    assert!(stats.completed);
}

#[test]
fn same_seed_gives_the_same_bytes() {
    let cfg = short_config(20.0);
    let (a, _) = record(&cfg, 11, RecorderOptions::default());
    let (b, _) = record(&cfg, 11, RecorderOptions::default());
    assert!(
        a == b,
        "two recordings of seed 11 differ ({} vs {} bytes)",
        a.len(),
        b.len()
    );
    let (c, _) = record(&cfg, 12, RecorderOptions::default());
    assert!(a != c);
}

#[test]
fn tampered_action_is_found_at_its_tick() {
    let cfg = short_config(20.0);
    let (bytes, _) = record(&cfg, 3, RecorderOptions::default());
    let mut rec = Recording::read(&bytes).unwrap();
    // Make a blue robot walk where it stood still (or stand where it walked)
    // from tick 50 on: the state after tick 50 must differ.
    let tampered = 50;
    let a = &mut rec.actions[tampered].actions[1];
    *a = if *a == Action::Forward {
        Action::TurnLeft
    } else {
        Action::Forward
    };
    match replay(&rec).unwrap() {
        ReplayOutcome::Diverged {
            tick,
            recorded,
            replayed,
        } => {
            assert_eq!(
                tick,
                Tick::new(tampered as u64 + 1),
                "the state after the tampered tick"
            );
            assert_ne!(recorded.state_hash, replayed.state_hash);
        }
        other => panic!("tampering went unnoticed: {other:?}"),
    }
}

#[test]
fn cut_short_recording_keeps_completed_chunks() {
    let cfg = short_config(30.0);
    // Small chunks so a cut in the middle of the file leaves several whole.
    let opts = RecorderOptions {
        chunk_size: 16 * 1024,
        ..RecorderOptions::default()
    };
    let (bytes, _) = record(&cfg, 5, opts);
    let cut = &bytes[..bytes.len() * 6 / 10];
    let rec = Recording::read(cut).unwrap();
    assert!(rec.truncated.is_some(), "a cut file must say so");
    assert!(rec.stats.is_none());
    assert!(!rec.actions.is_empty() && rec.actions.len() < 300);
    match replay(&rec).unwrap() {
        ReplayOutcome::Identical { ticks, truncated } => {
            assert!(truncated);
            assert_eq!(ticks as usize, rec.actions.len());
        }
        other => panic!("replay of the completed part diverged: {other:?}"),
    }
}

#[test]
fn garbage_is_not_a_recording() {
    assert!(Recording::read(b"not an mcap file at all").is_err());
}

/// The Foxglove channels are the SDK's: protobuf messages of its types under
/// its schemas (published name, `protobuf`, the SDK's descriptor), with the
/// scene and every tick's transforms in them; the naosoccer channels stay
/// JSON.
#[test]
fn foxglove_channels_are_the_sdks_protobuf_types() {
    use foxglove::messages::{FrameTransforms, SceneUpdate};
    use foxglove::{Decode, Encode};

    let cfg = short_config(5.0);
    let (bytes, _) = record(&cfg, 2, RecorderOptions::default());
    let (mut scenes, mut tfs, mut json) = (0, 0, 0);
    for msg in mcap::MessageStream::new(&bytes).unwrap() {
        let msg = msg.unwrap();
        let ch = &msg.channel;
        let schema = ch.schema.as_ref().expect("every channel has a schema");
        let sdk = |s: foxglove::Schema| {
            assert_eq!(schema.name, s.name, "{}", ch.topic);
            assert_eq!(schema.encoding, "protobuf", "{}", ch.topic);
            assert_eq!(schema.data.as_ref(), s.data.as_ref(), "{}", ch.topic);
            assert_eq!(ch.message_encoding, "protobuf", "{}", ch.topic);
        };
        match ch.topic.as_str() {
            "/foxglove/scene" => {
                sdk(SceneUpdate::get_schema().unwrap());
                let s = SceneUpdate::decode(msg.data.as_ref()).unwrap();
                let robots = s.entities.iter().filter(|e| e.id.starts_with("robot_"));
                assert_eq!(robots.count(), 8);
                assert!(s.entities.iter().any(|e| e.id == "pitch"));
                assert!(s.entities.iter().any(|e| e.id == "ball"));
                scenes += 1;
            }
            "/foxglove/tf" => {
                sdk(FrameTransforms::get_schema().unwrap());
                let t = FrameTransforms::decode(msg.data.as_ref()).unwrap();
                assert_eq!(t.transforms.len(), 9);
                // Stamped with game time, as the message is logged.
                let stamp = t.transforms[0].timestamp.unwrap();
                assert_eq!(stamp.total_nanos(), msg.log_time);
                tfs += 1;
            }
            topic => {
                assert_eq!(ch.message_encoding, "json", "{topic}");
                assert_eq!(schema.encoding, "jsonschema", "{topic}");
                serde_json::from_slice::<serde_json::Value>(&msg.data).unwrap();
                json += 1;
            }
        }
    }
    assert_eq!((scenes, tfs), (1, 51));
    assert!(json > 100);
}

/// Rewrites a recording message by message with `/match/meta`'s `format`
/// set to `format`.
fn with_format(bytes: &[u8], format: u32) -> Vec<u8> {
    let mut out = mcap::Writer::new(Cursor::new(Vec::new())).unwrap();
    let mut channels = std::collections::BTreeMap::new();
    for msg in mcap::MessageStream::new(bytes).unwrap() {
        let msg = msg.unwrap();
        let ch = &msg.channel;
        let id = *channels.entry(ch.id).or_insert_with(|| {
            let s = ch.schema.as_ref().unwrap();
            let schema = out.add_schema(&s.name, &s.encoding, &s.data).unwrap();
            out.add_channel(schema, &ch.topic, &ch.message_encoding, &ch.metadata)
                .unwrap()
        });
        let mut data = msg.data.to_vec();
        if ch.topic == "/match/meta" {
            let mut meta: MatchMeta = serde_json::from_slice(&data).unwrap();
            meta.format = format;
            data = serde_json::to_vec(&meta).unwrap();
        }
        let header = mcap::records::MessageHeader {
            channel_id: id,
            sequence: msg.sequence,
            log_time: msg.log_time,
            publish_time: msg.publish_time,
        };
        out.write_to_known_channel(&header, &data).unwrap();
    }
    out.finish().unwrap();
    out.into_inner().into_inner()
}

/// Format 3 changed only the Foxglove channels: a format-2 recording still
/// reads and replays; format 1 and formats newer than this build's are
/// refused.
#[test]
fn format_2_still_replays_and_others_are_refused() {
    assert_eq!(naosoccer_record::RECORDING_FORMAT, 3);
    let cfg = short_config(10.0);
    let (bytes, _) = record(&cfg, 4, RecorderOptions::default());
    let rec = Recording::read(&with_format(&bytes, 2)).unwrap();
    assert_eq!(rec.meta.format, 2);
    assert_eq!(
        replay(&rec).unwrap(),
        ReplayOutcome::Identical {
            ticks: 100,
            truncated: false
        }
    );
    for format in [1, 4] {
        let err = Recording::read(&with_format(&bytes, format)).unwrap_err();
        assert_eq!(
            err.to_string(),
            format!("recording format {format} is not supported (this build reads 2 to 3)")
        );
    }
}

/// Protocol 1.5's `set_state`: a change recorded before the tick it
/// preceded is re-applied there by replay, which reproduces every state;
/// a recording whose change is moved to another tick diverges at that
/// point. A recording with no change has no `/match/set_state` channel.
#[test]
fn recorded_state_changes_are_replayed_at_their_tick() {
    use naosoccer_proto::{BallPlacement, RobotPlacement, StateChange};
    let cfg = short_config(6.0);
    let seed = 4;
    let mut m = Match::new(&cfg, seed).unwrap();
    let mut policies: Vec<_> = RobotId::all()
        .map(|r| PolicyKind::Scripted.build(seed, r))
        .collect();
    let mut rec =
        Recorder::in_memory(&meta(&cfg, seed, &m), &m, RecorderOptions::default()).unwrap();
    let change = |t: u64| StateChange {
        ball: Some(BallPlacement {
            x: -1.0 + 0.1 * t as f32,
            y: 0.7,
            vx: 0.5,
            vy: -1.0,
        }),
        robots: vec![RobotPlacement {
            robot: t % 8,
            x: 0.5,
            y: -1.5,
            heading: Some(2.0),
            fallen: t.is_multiple_of(2),
        }],
    };
    let mut obs = blank_observation();
    while !m.is_finished() {
        let t = m.tick().get();
        if t == 0 || t == 13 || t == 31 {
            m.set_state(&change(t)).unwrap();
            rec.set_state(m.tick(), &change(t)).unwrap();
        }
        let mut actions = [Action::Stay; ROBOTS];
        for r in RobotId::all() {
            m.observe_into(r.team(), r.player(), &mut obs);
            actions[r.index()] = policies[r.index()].act(&obs);
        }
        let events = m.step(&actions).to_vec();
        rec.tick(&m, &actions, &events).unwrap();
    }
    let (summary, sink) = rec.finish(&m).unwrap();
    assert_eq!(summary.messages.get("/match/set_state"), Some(&3));
    let bytes = sink.into_bytes().unwrap();
    let rec = Recording::read(&bytes).unwrap();
    let ticks: Vec<u64> = rec.set_states.iter().map(|s| s.tick.get()).collect();
    assert_eq!(ticks, [0, 13, 31]);
    assert_eq!(rec.set_states[1].change(), change(13));
    assert_eq!(
        replay(&rec).unwrap(),
        ReplayOutcome::Identical {
            ticks: 60,
            truncated: false
        }
    );
    let mut moved = rec.clone();
    moved.set_states[1].tick = Tick::new(14);
    match replay(&moved).unwrap() {
        ReplayOutcome::Diverged { tick, .. } => assert_eq!(tick, Tick::new(14)),
        other => panic!("{other:?}"),
    }
    let (plain, _) = record(&cfg, seed, RecorderOptions::default());
    let plain = Recording::read(&plain).unwrap();
    assert!(plain.set_states.is_empty());
    assert!(!plain.counts.contains_key("/match/set_state"));
}
