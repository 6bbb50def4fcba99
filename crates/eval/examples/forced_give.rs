//! What passing costs a learned team that dribbles: the team plays as it
//! chose, except that a robot of it with the ball in kick reach and a
//! teammate to give to (`give_target`) outside set plays gives: it keeps
//! to the `give` step (`give_action`: line up on the teammate, then the
//! protocol's `pass`) until it kicks, the ball is more than
//! `GIVE_RELEASE_BALL` away or there is no one to give to, as a held
//! `give` does. With `--plain` the team plays as it chose throughout, for
//! comparison. Prints results, goals, aimed kicks and passes a match.
//!
//! ```sh
//! cargo run --release -p naosoccer-eval --example forced_give -- \
//!     ppo:assets/policies/ppo-team-seed1 scripted 10
//! ```
//!
//! The team plays blue in every match; match seeds are 1, 2, ... N; the
//! opponent is a built-in team (`scripted`, `scripted:5`, `random`, ...).

mod common;

use std::process::ExitCode;

use naosoccer_eval::eval::LONG_PASS_METRES;
use naosoccer_policy::actions::{give_action, give_target, GIVE_RELEASE_BALL};
use naosoccer_policy::{load_policy_for_match, Policy, PolicyKind};
use naosoccer_proto::{Action, Event, RobotId, Team, PLAYERS_PER_TEAM, ROBOTS};
use naosoccer_referee::{Match, MatchConfig};

#[derive(Default)]
struct Totals {
    results: [u64; 3],
    goals: [u64; 2],
    aimed_kicks: u64,
    passes: u64,
    aimed_passes: u64,
    long_passes: u64,
}

fn main() -> ExitCode {
    let mut args: Vec<String> = std::env::args().collect();
    let plain = args.iter().any(|a| a == "--plain");
    args.retain(|a| a != "--plain");
    let (team, opponent, n) = match args.as_slice() {
        [_, t, o, n] => match n.parse::<u64>() {
            Ok(n) if n > 0 => (t.clone(), o.clone(), n),
            _ => {
                eprintln!("MATCHES must be a positive integer, not {n:?}");
                return ExitCode::from(2);
            }
        },
        _ => {
            eprintln!("usage: forced_give [--plain] TEAM OPPONENT MATCHES  (TEAM ppo:DIR, OPPONENT a built-in team)");
            return ExitCode::from(2);
        }
    };
    let kind: PolicyKind = match opponent.parse() {
        Ok(k) => k,
        Err(e) => {
            eprintln!("{opponent}: {e} (forced_give plays a built-in opponent)");
            return ExitCode::FAILURE;
        }
    };
    let cfg = MatchConfig::default();
    let half = [cfg.sim.field_length / 2.0, cfg.sim.field_width / 2.0];
    let reach = naosoccer_policy::obs::KickReach::default();
    let mut tot = Totals::default();
    for seed in 1..=n {
        let (mut m, mut blue) = match (Match::new(&cfg, seed), load_policy_for_match(&team, seed)) {
            (Ok(m), Ok(b)) => (m, b),
            (Err(e), _) => {
                eprintln!("match {seed}: {e}");
                return ExitCode::FAILURE;
            }
            (_, Err(e)) => {
                eprintln!("{team}: {e}");
                return ExitCode::FAILURE;
            }
        };
        let mut red: Vec<Box<dyn Policy>> = (0..PLAYERS_PER_TEAM)
            .map(|p| kind.build(seed, RobotId::new(Team::Red, p).expect("a player")))
            .collect();
        let mut giving = [false; PLAYERS_PER_TEAM];
        while !m.is_finished() {
            let blue_obs: Vec<_> = (0..PLAYERS_PER_TEAM)
                .map(|p| m.observe(Team::Blue, p))
                .collect();
            let mut joint = [Action::Stay; ROBOTS];
            blue.act_batch(&blue_obs, &mut joint[..PLAYERS_PER_TEAM]);
            for (p, policy) in red.iter_mut().enumerate() {
                joint[PLAYERS_PER_TEAM + p] = policy.act(&m.observe(Team::Red, p));
            }
            for (p, o) in blue_obs.iter().enumerate() {
                let me = o.me();
                if plain || me.fallen || me.busy || o.set_play.is_some() {
                    continue;
                }
                let ball = (o.ball.x - me.x).hypot(o.ball.y - me.y);
                let target = give_target(o).is_some();
                if giving[p] && (ball > GIVE_RELEASE_BALL || !target) {
                    giving[p] = false;
                }
                if !giving[p] && target && reach.in_reach(o) {
                    giving[p] = true;
                }
                if giving[p] {
                    joint[p] = give_action(o, half, &reach);
                    giving[p] = joint[p] != Action::Pass;
                }
            }
            for e in m.step(&joint) {
                match e {
                    Event::Kick {
                        robot,
                        receiver: Some(_),
                        ..
                    } if robot.team() == Team::Blue => tot.aimed_kicks += 1,
                    Event::Pass {
                        from,
                        aimed,
                        distance,
                        ..
                    } if from.team() == Team::Blue => {
                        tot.passes += 1;
                        tot.aimed_passes += u64::from(*aimed);
                        tot.long_passes += u64::from(*distance >= LONG_PASS_METRES);
                    }
                    _ => {}
                }
            }
        }
        let score = m.score();
        let (b, r) = (u64::from(score.blue), u64::from(score.red));
        tot.goals[0] += b;
        tot.goals[1] += r;
        tot.results[if b > r {
            0
        } else if b == r {
            1
        } else {
            2
        }] += 1;
    }
    let per = |k: u64| k as f64 / n as f64;
    println!(
        "{team} (blue{}) v {opponent}, match seeds 1..={n}",
        if plain {
            ", as it chose"
        } else {
            ", giving at every chance"
        }
    );
    println!(
        "W/D/L {}/{}/{}, goals {:.2} : {:.2} a match",
        tot.results[0],
        tot.results[1],
        tot.results[2],
        per(tot.goals[0]),
        per(tot.goals[1])
    );
    println!(
        "a match: aimed kicks {:.2}, passes {:.2} (aimed {:.2}, of {LONG_PASS_METRES} m or more {:.2})",
        per(tot.aimed_kicks),
        per(tot.passes),
        per(tot.aimed_passes),
        per(tot.long_passes)
    );
    ExitCode::SUCCESS
}
