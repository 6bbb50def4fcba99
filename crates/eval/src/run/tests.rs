//! A match is the same alone or in a batch, on one thread or two; a trained
//! team in a batch plays as one policy per robot would.

use std::ops::ControlFlow;
use std::path::PathBuf;

use naosoccer_policy::{load_policy_for_match, Policy, PolicyKind};
use naosoccer_proto::{Action, Observation, RobotId, Team, ROBOTS};
use naosoccer_referee::{blank_observation, Match, MatchConfig, Scenario};

use super::*;

fn short() -> MatchConfig {
    MatchConfig {
        minutes: 0.25,
        ..MatchConfig::default()
    }
}

fn shipped(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../assets")
        .join(name)
}

/// A trained team, shipped with the repository.
fn ppo() -> String {
    format!("ppo:{}", shipped("policies/ppo-team-seed1").display())
}

fn corner() -> Scenario {
    Scenario::from_file(&shipped("scenarios/corner.toml")).unwrap()
}

/// Whole matches and scenario starts, either side blue, in one batch on two
/// threads: each is the match [`play_one`] plays alone.
#[test]
fn a_match_is_the_same_alone_or_in_a_batch() {
    let cfg = short();
    let corner = corner();
    let fixtures: Vec<Fixture> = (0..4)
        .map(|i| Fixture {
            index: 10 + i,
            seed: 100 + i as u64,
            swapped: i % 2 == 1,
            scenario: (i >= 2).then_some((&corner, [Team::Blue, Team::Red][i % 2])),
        })
        .collect();
    let sides = || {
        (
            Side::parse(&ppo()).unwrap(),
            Side::Builtin(PolicyKind::Random),
        )
    };
    let (mut first, mut second) = sides();
    let mut batch = Batch::new(&cfg, &mut first, &mut second, fixtures.clone()).unwrap();
    assert_eq!(batch.len(), 4);
    assert!(batch.play(2, &|| false));
    let together = batch.results();
    for (f, p) in fixtures.iter().zip(&together) {
        let (mut first, mut second) = sides();
        let mut ticks = 0;
        let alone = play_one(&cfg, &mut first, &mut second, *f, |_| {
            ticks += 1;
            ControlFlow::Continue(())
        })
        .unwrap();
        assert_eq!((p.index, p.seed, p.swapped), (f.index, f.seed, f.swapped));
        assert_eq!(p.state_hash, alone.state_hash, "match {}", f.index);
        assert_eq!((p.ticks, p.events), (alone.ticks, alone.events));
        assert_eq!(p.ending.is_some(), f.scenario.is_some());
        // Watched every tick, from the kick-off or the scenario's start.
        assert_eq!(ticks, p.ending.map_or(p.ticks, |e| e.ticks));
    }
}

/// The trained team decides for all its robots of all matches at once;
/// played one policy per robot (as `naosoccer client` plays it), loaded
/// for the match's seed, it plays the same matches, bit for bit.
#[test]
fn a_trained_team_in_a_batch_plays_as_one_policy_per_robot() {
    let cfg = short();
    let spec = ppo();
    let mut first = Side::parse(&spec).unwrap();
    let mut second = Side::Builtin(PolicyKind::Scripted);
    let fixtures = (0..3).map(|i| Fixture {
        index: i,
        seed: 7 + i as u64,
        swapped: i == 1,
        scenario: None,
    });
    let mut batch = Batch::new(&cfg, &mut first, &mut second, fixtures).unwrap();
    assert!(batch.play(1, &|| false));
    for p in batch.results() {
        let mut m = Match::new(&cfg, p.seed).unwrap();
        let trained = if p.swapped { Team::Red } else { Team::Blue };
        let mut policies: Vec<Box<dyn Policy>> = RobotId::all()
            .map(|r| {
                if r.team() == trained {
                    load_policy_for_match(&spec, p.seed).unwrap()
                } else {
                    PolicyKind::Scripted.build(p.seed, r)
                }
            })
            .collect();
        let mut obs: Observation = blank_observation();
        let mut actions = [Action::Stay; ROBOTS];
        let mut events = 0;
        while !m.is_finished() {
            for r in RobotId::all() {
                m.observe_into(r.team(), r.player(), &mut obs);
                actions[r.index()] = policies[r.index()].act(&obs);
            }
            events += m.step(&actions).len() as u64;
        }
        assert_eq!(p.state_hash, m.state_hash(), "match {}", p.index);
        assert_eq!((p.score, p.events), (m.score(), events));
    }
}

/// `stop` is asked before every tick: play stops there, unfinished.
#[test]
fn play_stops_when_asked() {
    let cfg = short();
    let mut first = Side::Builtin(PolicyKind::Scripted);
    let mut second = Side::Builtin(PolicyKind::Idle);
    let mut batch = Batch::new(
        &cfg,
        &mut first,
        &mut second,
        [Fixture::kick_off(1), Fixture::kick_off(2)],
    )
    .unwrap();
    let asked = std::cell::Cell::new(0);
    let stop = || {
        asked.set(asked.get() + 1);
        asked.get() > 5
    };
    assert!(!batch.play(1, &stop));
    assert!(!batch.is_over());
    assert!(batch.results().iter().all(|p| p.ticks == 5));
    assert_eq!(batch.ticked(1).m.tick().get(), 5);
}
