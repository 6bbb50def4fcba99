//! Record matches in process and replay them: identical states, repeatable
//! bytes, a tampered action found at its tick, a cut-short file still read.

use std::io::Cursor;

use naosoccer_client::policy::PolicyKind;
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
    let mut rec = Recorder::new(Cursor::new(Vec::new()), &meta(cfg, seed, &m), &m, opts).unwrap();
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
    let (summary, cursor) = rec.finish(&m).unwrap();
    (cursor.into_inner(), summary)
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
