//! Seeds, intervals, both sides, long passes, blocks and merges.

use naosoccer_policy::PolicyKind;
use naosoccer_proto::{Action, Event, PerTeam, RobotId, ROBOTS};
use naosoccer_referee::{Match, MatchConfig};
use serde_json::json;

use super::*;

#[test]
fn wilson_interval_matches_hand_computed_values() {
    // Values from the closed form, z = 1.96.
    for (k, n, low, high) in [
        (0, 10, 0.0, 0.277_540),
        (5, 10, 0.236_590, 0.763_410),
        (8, 10, 0.490_157, 0.943_319),
        (100, 100, 0.963_005, 1.0),
        (80, 100, 0.711_169, 0.866_634),
    ] {
        let r = Rate::wilson(k, n);
        assert!(
            (r.low - low).abs() < 1e-5 && (r.high - high).abs() < 1e-5,
            "{k}/{n}: {r:?}"
        );
        assert!(r.low <= r.rate && r.rate <= r.high);
    }
    assert!(Rate::wilson(0, 0).rate.is_nan());
    assert_eq!(Rate::wilson(8, 10).to_string(), "80.0 [49.0, 94.3]");
}

#[test]
fn evaluation_seeds_never_meet_training_seeds() {
    let mut eval = std::collections::BTreeSet::new();
    for seed in 0..8 {
        for i in 0..200 {
            let s = eval_match_seed(seed, i);
            assert_ne!(s & EVAL_SEED_BIT, 0);
            eval.insert(s);
            for episode in 0..4 {
                assert_eq!(episode_seed(seed, i, episode) & EVAL_SEED_BIT, 0);
            }
        }
    }
    // Distinct across seeds and matches.
    assert_eq!(eval.len(), 8 * 200);
    // The legacy scheme is the old training derivation, top bit and all.
    assert_eq!(
        SeedScheme::Legacy.match_seed(7, 3),
        legacy_episode_seed(7, 3, 0)
    );
    assert_eq!(
        episode_seed(7, 3, 0),
        legacy_episode_seed(7, 3, 0) & !EVAL_SEED_BIT
    );
}

fn short_config() -> MatchConfig {
    MatchConfig {
        minutes: 0.25,
        ..MatchConfig::default()
    }
}

#[test]
fn both_sides_swaps_every_other_match_and_keeps_each_team_under_its_name() {
    let cfg = short_config();
    let plan = EvalPlan {
        matches: 4,
        first_match: 0,
        seed: 3,
        both_sides: true,
        seeds: SeedScheme::Eval,
    };
    let scripted = || Side::Builtin(PolicyKind::Scripted);
    let random = || Side::Builtin(PolicyKind::Random);
    let both = play_matches(&cfg, &mut scripted(), &mut random(), &plan, 1).unwrap();
    assert_eq!(
        both.iter().map(|r| r.swapped).collect::<Vec<_>>(),
        [false, true, false, true]
    );
    // A swapped match is the match with the teams named the other way
    // round: same seed, same play, bit for bit.
    let plain = EvalPlan {
        both_sides: false,
        ..plan
    };
    let reversed = play_matches(&cfg, &mut random(), &mut scripted(), &plain, 1).unwrap();
    let straight = play_matches(&cfg, &mut scripted(), &mut random(), &plain, 1).unwrap();
    for i in 0..4 {
        let expect = if i % 2 == 1 {
            &reversed[i]
        } else {
            &straight[i]
        };
        assert_eq!(both[i].seed, expect.seed);
        assert_eq!(both[i].score, expect.score);
        assert_eq!(both[i].state_hash, expect.state_hash);
    }
    let records: Vec<_> = both.iter().map(MatchResult::record).collect();
    let [first, second] = summarise(&records, "scripted", "random");
    assert_eq!(
        (first.name.as_str(), second.name.as_str()),
        ("scripted", "random")
    );
    assert_eq!(first.as_blue.matches(), 2);
    assert_eq!(first.as_red.matches(), 2);
    let goals: u32 = both.iter().map(|r| r.goals_of(true)).sum();
    let by_colour: u32 = (0..4)
        .map(|i| {
            if i % 2 == 1 {
                reversed[i].score.red
            } else {
                straight[i].score.blue
            }
        })
        .sum();
    assert_eq!(goals, by_colour);
    assert!((first.goals.mean - f64::from(goals) / 4.0).abs() < 1e-12);
    assert_eq!(first.wins, second.losses);
    assert_eq!(first.win_rate, Rate::wilson(first.wins, 4));
}

/// Long passes are the `pass` events of at least `LONG_PASS_METRES`,
/// by the passer's team, recounted here from a replay of each match;
/// scripted teams make both kinds, so a count of all passes or of none
/// fails.
#[test]
fn long_passes_count_the_pass_events_of_a_metre_or_more() {
    let cfg = MatchConfig {
        minutes: 5.0,
        ..MatchConfig::default()
    };
    let plan = EvalPlan {
        matches: 2,
        first_match: 0,
        seed: 5,
        both_sides: true,
        seeds: SeedScheme::Eval,
    };
    let scripted = || Side::Builtin(PolicyKind::Scripted);
    let results = play_matches(&cfg, &mut scripted(), &mut scripted(), &plan, 1).unwrap();
    let (mut long, mut short) = (0, 0);
    for r in &results {
        let mut m = Match::new(&cfg, r.seed).unwrap();
        let mut policies: Vec<_> = RobotId::all()
            .map(|id| PolicyKind::Scripted.build(m.seed(), id))
            .collect();
        let mut obs = naosoccer_referee::blank_observation();
        let mut actions = [Action::Stay; ROBOTS];
        let mut by_colour = PerTeam::<u32>::default();
        while !m.is_finished() {
            for id in RobotId::all() {
                m.observe_into(id.team(), id.player(), &mut obs);
                actions[id.index()] = policies[id.index()].act(&obs);
            }
            for e in m.step(&actions) {
                if let Event::Pass { from, distance, .. } = *e {
                    if distance >= LONG_PASS_METRES {
                        *by_colour.get_mut(from.team()) += 1;
                        long += 1;
                    } else {
                        short += 1;
                    }
                }
            }
        }
        assert_eq!(m.state_hash(), r.state_hash, "the replay is the match");
        assert_eq!(r.long_passes, by_colour);
        let rec = r.record();
        for first in [true, false] {
            let k = usize::from(!first);
            assert_eq!(rec.long_passes[k], *by_colour.get(r.team_of(first)));
            assert!(rec.long_passes[k] <= rec.passes[k]);
        }
    }
    assert!(long > 0 && short > 0, "long {long}, short {short}");
    let records: Vec<_> = results.iter().map(MatchResult::record).collect();
    let [first, second] = summarise(&records, "a", "b");
    let total = first.long_passes.mean * 2.0 + second.long_passes.mean * 2.0;
    assert!((total - f64::from(long)).abs() < 1e-9);
    // Reports written before long passes were counted still read.
    let mut old = serde_json::to_value(&records[0]).unwrap();
    old.as_object_mut().unwrap().remove("long_passes");
    let back: MatchRecord = serde_json::from_value(old).unwrap();
    assert_eq!(back.long_passes, [0, 0]);
}

/// A block of an evaluation plays its matches as the whole run does, by
/// global index; the reports of blocks merge into the whole run's,
/// through their JSON; mismatched and incomplete sets are refused.
#[test]
fn blocks_play_the_whole_runs_matches_and_merge_into_its_report() {
    let cfg = short_config();
    let names = ["scripted".to_string(), "random".to_string()];
    let whole = EvalPlan {
        matches: 5,
        first_match: 0,
        seed: 9,
        both_sides: true,
        seeds: SeedScheme::Eval,
    };
    let play = |plan: EvalPlan| {
        let mut a = Side::Builtin(PolicyKind::Scripted);
        let mut b = Side::Builtin(PolicyKind::Random);
        let results = play_matches(&cfg, &mut a, &mut b, &plan, 2).unwrap();
        // Through the JSON, as --merge reads it.
        let json = EvalReport::new(names.clone(), plan, &cfg, &results, 1.0).to_json();
        EvalReport::from_json("part", &json).unwrap()
    };
    let full = play(whole);
    let block = |first_match, matches| {
        play(EvalPlan {
            first_match,
            matches,
            ..whole
        })
    };
    let (a, b, c) = (block(0, 2), block(2, 2), block(4, 1));
    assert_eq!(b.records[..], full.records[2..4]);
    assert_eq!(b.records[1].index, 3);
    assert!(b.records[1].swapped);
    let label = |s: &str, r: &EvalReport| (s.to_string(), r.clone());
    let merged = EvalReport::merge(&[label("c", &c), label("a", &a), label("b", &b)]).unwrap();
    assert_eq!(merged.wall_seconds, 3.0);
    assert_eq!(
        EvalReport {
            wall_seconds: 1.0,
            ..merged.clone()
        },
        full
    );
    assert_eq!(merged.to_json()["blue"], full.to_json()["blue"]);
    // Blocks 2..5 alone are the run of --first-match 2 --matches 3.
    let tail = EvalReport::merge(&[label("b", &b), label("c", &c)]).unwrap();
    assert_eq!(tail.records, block(2, 3).records);
    assert!(tail
        .table()
        .starts_with("3 matches (numbers 2 to 4 of the evaluation)"));

    let err = |parts: &[(String, EvalReport)]| EvalReport::merge(parts).unwrap_err();
    assert!(matches!(
        err(&[label("a", &a), label("c", &c)]),
        ReportError::Gap { from: 2, to: 3, .. }
    ));
    assert!(matches!(
        err(&[label("a", &a), label("a2", &block(1, 2)), label("c", &c)]),
        ReportError::Overlap { index: 1, .. }
    ));
    let mut other = b.clone();
    other.names[1] = "idle".into();
    assert!(matches!(
        err(&[label("a", &a), label("b", &other)]),
        ReportError::Mismatch { field: "--red", .. }
    ));
    other = b.clone();
    other.config_hash ^= 1;
    assert!(matches!(
        err(&[label("a", &a), label("b", &other)]),
        ReportError::Mismatch {
            field: "config_hash",
            ..
        }
    ));
    assert!(matches!(err(&[]), ReportError::Empty));
    // A record that is not its plan's match is refused on reading.
    let mut json = b.to_json();
    json["results"][0]["seed"] = json!(1);
    assert!(matches!(
        EvalReport::from_json("b", &json),
        Err(ReportError::Format { .. })
    ));
    let mut json = b.to_json();
    json.as_object_mut().unwrap().remove("results");
    assert!(EvalReport::from_json("b", &json).is_err());
    // Another match length is another configuration.
    let longer = MatchConfig {
        minutes: 0.5,
        ..cfg.clone()
    };
    assert_ne!(config_hash(&longer), config_hash(&cfg));
}

#[test]
fn confidence_interval_uses_student_t() {
    let e = Estimate::of(&[1.0, 2.0, 3.0]);
    assert!((e.mean - 2.0).abs() < 1e-12);
    // sd 1, n 3, t(2) = 4.303.
    assert!((e.ci95 - 4.303 / 3f64.sqrt()).abs() < 1e-9);
    assert!(Estimate::of(&[5.0]).ci95.is_nan());
    assert_eq!(t95(1000), 1.96);
}
