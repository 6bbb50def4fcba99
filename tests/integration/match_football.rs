//! Whole 10-minute matches, scripted against scripted, over a handful of
//! seeds: the result must look like football (goals for both sides, the ball
//! controlled by one team or the other, passes, falls), and a match must be
//! repeatable from its seed.

use naosoccer_eval::run::{play_match, MatchOutcome};
use naosoccer_policy::PolicyKind;
use naosoccer_referee::MatchConfig;

const SEEDS: [u64; 4] = [1, 2, 3, 4];

fn play(seed: u64) -> MatchOutcome {
    play_match(
        &MatchConfig::default(),
        seed,
        &PolicyKind::Scripted,
        &PolicyKind::Scripted,
        |_| {},
    )
    .expect("default match")
}

#[test]
fn scripted_matches_look_like_football() {
    let outcomes: Vec<MatchOutcome> = SEEDS.iter().map(|&s| play(s)).collect();
    for o in &outcomes {
        let (b, r) = (&o.stats.blue, &o.stats.red);
        println!(
            "seed {}: {}-{}  control {:.2}/{:.2}  passes {}/{}  shots {}/{}  falls {}/{}  out {}/{}  ({:.2} s)",
            o.seed,
            o.score.blue,
            o.score.red,
            b.control_rate,
            r.control_rate,
            b.passes,
            r.passes,
            b.shots,
            r.shots,
            b.falls,
            r.falls,
            b.out_of_bounds,
            r.out_of_bounds,
            o.wall_seconds
        );
    }
    for o in &outcomes {
        assert_eq!(o.ticks, 6000, "a 10-minute match at 10 Hz");
        assert!((o.sim_seconds - 600.0).abs() < 1e-6);
        assert_eq!(
            (o.score.blue, o.score.red),
            (o.stats.blue.goals, o.stats.red.goals)
        );
        let sum = o.stats.blue.control_rate + o.stats.red.control_rate;
        assert!(
            (sum - 1.0).abs() < 1e-9,
            "seed {}: control rates sum to {sum}",
            o.seed
        );
        assert!(
            o.stats.blue.shots + o.stats.red.shots > 0,
            "seed {}: nobody kicked",
            o.seed
        );
    }
    let total = |f: &dyn Fn(&MatchOutcome) -> u32| outcomes.iter().map(f).sum::<u32>();
    assert!(total(&|o| o.score.blue) > 0, "blue never scored");
    assert!(total(&|o| o.score.red) > 0, "red never scored");
    assert!(
        total(&|o| o.stats.blue.passes + o.stats.red.passes) > 0,
        "no passes"
    );
    assert!(
        total(&|o| o.stats.blue.falls + o.stats.red.falls) > 0,
        "no falls"
    );
}

#[test]
fn a_match_is_repeatable_from_its_seed() {
    let cfg = MatchConfig {
        minutes: 1.0,
        ..MatchConfig::default()
    };
    let run = |seed| {
        let mut o = play_match(
            &cfg,
            seed,
            &PolicyKind::Scripted,
            &PolicyKind::Random,
            |_| {},
        )
        .unwrap();
        o.wall_seconds = 0.0;
        o
    };
    let a = run(21);
    assert_eq!(a, run(21));
    assert_ne!(a.state_hash, run(22).state_hash);
}
