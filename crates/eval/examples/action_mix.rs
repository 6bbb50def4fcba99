//! Which of its actions a learned team chooses, and where: at every control
//! tick outside set plays where one of the team's robots is free to decide
//! (standing, not kicking), how often each network action was allowed
//! (not masked) and the mean probability the team's policy gave it then,
//! split by whether the robot had the ball in kick reach. Read from the
//! policy's own distribution (`LearnedPolicy::probabilities_for`), so it
//! says what the team prefers, not what one sample drew.
//!
//! ```sh
//! cargo run --release -p naosoccer-eval --example action_mix -- \
//!     ppo:assets/policies/ppo-team-seed1 scripted 10
//! ```
//!
//! The team plays blue in every match; match seeds are 1, 2, ... N.

mod common;

use std::ops::ControlFlow;
use std::process::ExitCode;

use common::pct;
use naosoccer_policy::actions::{banned_actions, is_free, NetAction, MAX_ACTIONS};
use naosoccer_policy::LearnedPolicy;
use naosoccer_proto::{Team, PLAYERS_PER_TEAM};
use naosoccer_referee::MatchConfig;

#[derive(Default)]
struct Tally {
    /// [ball in reach] decision ticks.
    ticks: [u64; 2],
    /// [ball in reach][action]: ticks the action was allowed.
    allowed: [[u64; MAX_ACTIONS]; 2],
    /// [ball in reach][action]: summed probability where allowed.
    prob: [[f64; MAX_ACTIONS]; 2],
}

fn main() -> ExitCode {
    let (team, opponent, n) = match common::team_opponent_matches("action_mix") {
        Ok(a) => a,
        Err(code) => return code,
    };
    let policy = match LearnedPolicy::load(&team) {
        Ok(p) => p,
        Err(e) => {
            eprintln!("{team}: {e} (action_mix reads a learned team)");
            return ExitCode::FAILURE;
        }
    };
    let actions = policy.actions();
    let decision = policy.decision();
    let reach = policy.scale().kick;
    let cfg = MatchConfig::default();
    let mut tally = Tally::default();
    for seed in 1..=n {
        let played = common::play_match(&cfg, &team, &opponent, seed, |t| {
            if t.m.set_play().is_some() {
                return ControlFlow::Continue(());
            }
            for p in 0..PLAYERS_PER_TEAM {
                let obs = t.m.observe(Team::Blue, p);
                if !is_free(&obs) {
                    continue;
                }
                let in_reach = reach.in_reach(&obs) as usize;
                let bans = decision.map_or(0, |d| banned_actions(&obs, in_reach == 1, &d));
                let probs = policy.probabilities_for(std::slice::from_ref(&obs));
                tally.ticks[in_reach] += 1;
                for (a, &pr) in probs.iter().enumerate().take(actions) {
                    let shoot_masked = a == NetAction::Shoot.index() && in_reach == 0;
                    if bans & (1 << a) == 0 && !shoot_masked {
                        tally.allowed[in_reach][a] += 1;
                        tally.prob[in_reach][a] += f64::from(pr);
                    }
                }
            }
            ControlFlow::Continue(())
        });
        if let Err(code) = played {
            return code;
        }
    }
    println!("{team} (blue) v {opponent}, match seeds 1..={n}: free robots' decision ticks outside set plays");
    for (k, label) in ["ball out of reach", "ball in kick reach"]
        .iter()
        .enumerate()
    {
        println!(
            "\n{label}: {} robot-ticks a match",
            tally.ticks[k] / n.max(1)
        );
        println!(
            "{:<12} {:>9} {:>22} {:>14}",
            "action", "allowed", "mean prob. if allowed", "share of all"
        );
        for (a, action) in NetAction::ALL.iter().enumerate().take(actions) {
            let allowed = tally.allowed[k][a];
            let mean = if allowed > 0 {
                tally.prob[k][a] / allowed as f64
            } else {
                0.0
            };
            println!(
                "{:<12} {:>8.1}% {:>22.4} {:>13.2}%",
                action.name(),
                pct(allowed, tally.ticks[k]),
                mean,
                100.0 * tally.prob[k][a] / tally.ticks[k].max(1) as f64
            );
        }
    }
    ExitCode::SUCCESS
}
