//! How often a team could pass, and whether it does: at every control tick
//! where one of its robots has the ball in kick reach (outside set plays),
//! whether the protocol's pass rule names a receiver
//! (`naosoccer_proto::pass_receiver`) and which action the robot then
//! applied; where there is no receiver, where the standing teammate nearest
//! the robot's heading was instead. And of the team's passes (the `pass`
//! events `eval` counts), how many followed a `pass` action and how many
//! another kick (a `shoot` that a teammate happened to reach).
//!
//! ```sh
//! cargo run --release -p naosoccer-eval --example pass_chances -- \
//!     ppo:assets/policies/ppo-team-seed3 scripted 20
//! ```
//!
//! The team plays blue in every match; match seeds are 1, 2, ... N (the
//! team's own sampling is keyed by them as in `eval`).

mod common;

use std::ops::ControlFlow;
use std::process::ExitCode;

use common::pct;
use naosoccer_eval::eval::LONG_PASS_METRES;
use naosoccer_eval::run::Side;
use naosoccer_policy::obs::KickReach;
use naosoccer_proto::{pass_receiver, Action, Event, Observation, Team, PLAYERS_PER_TEAM};
use naosoccer_referee::rules::wrap_angle;
use naosoccer_referee::MatchConfig;

/// Distance rows of the "no receiver" table (upper bounds, m).
const DIST_ROWS: [f32; 4] = [0.8, 2.0, 4.0, f32::INFINITY];
/// Angle columns of the table: |bearing off the heading| per this many rad.
const ANGLE_STEP: f32 = 0.4;
const ANGLE_COLS: usize = 8;

#[derive(Default)]
struct Tally {
    /// [receiver named][applied action index]
    actions: [[u64; Action::ALL.len()]; 2],
    /// No receiver: [distance row][angle column] of the standing teammate
    /// whose bearing from the ball is nearest the kicker's heading.
    nearest: [[u64; ANGLE_COLS]; DIST_ROWS.len()],
    /// No receiver and no teammate standing.
    all_down: u64,
    /// The team's `pass` events: [after a `pass` kick, after any other
    /// kick][shorter than 1 m, 1 m or more].
    passes: [[u64; 2]; 2],
}

impl Tally {
    fn count(&mut self, obs: &Observation, applied: Action) {
        let receiver = pass_receiver(obs);
        self.actions[receiver.is_some() as usize][applied.index()] += 1;
        if receiver.is_some() {
            return;
        }
        let me = obs.player.index();
        let heading = obs.own[me].heading;
        let nearest = obs
            .own
            .iter()
            .enumerate()
            .filter(|&(j, r)| j != me && !r.fallen)
            .map(|(_, r)| {
                let (dx, dy) = (r.x - obs.ball.x, r.y - obs.ball.y);
                (wrap_angle(dy.atan2(dx) - heading).abs(), dx.hypot(dy))
            })
            .min_by(|a, b| a.0.total_cmp(&b.0));
        match nearest {
            None => self.all_down += 1,
            Some((off, d)) => {
                let row = DIST_ROWS.iter().position(|&m| d < m).unwrap_or(0);
                let col = ((off / ANGLE_STEP) as usize).min(ANGLE_COLS - 1);
                self.nearest[row][col] += 1;
            }
        }
    }

    fn pass_event(&mut self, by_pass_action: bool, distance: f32) {
        self.passes[usize::from(!by_pass_action)][usize::from(distance >= LONG_PASS_METRES)] += 1;
    }

    fn print(&self, matches: u64) {
        let per = |k: u64| k as f64 / matches as f64;
        let [p, other] = self.passes;
        println!(
            "passes (the `pass` event): {:.2} a match ({:.2} of 1 m or more); after a `pass` action {:.2} ({:.2}), after another kick {:.2} ({:.2})",
            per(p[0] + p[1] + other[0] + other[1]),
            per(p[1] + other[1]),
            per(p[0] + p[1]),
            per(p[1]),
            per(other[0] + other[1]),
            per(other[1])
        );
        let total: u64 = self.actions.iter().flatten().sum();
        let with: u64 = self.actions[1].iter().sum();
        println!(
            "ticks with the ball in a robot's kick reach: {:.0} a match (robot-ticks), a receiver named at {:.1}% of them",
            total as f64 / matches as f64,
            pct(with, total)
        );
        for (named, row) in self.actions.iter().enumerate() {
            let n: u64 = row.iter().sum();
            print!(
                "  receiver {:<3} {n:>8} ticks:",
                if named == 1 { "yes" } else { "no" }
            );
            for a in Action::ALL {
                print!(" {} {:.1}%", a.name(), pct(row[a.index()], n));
            }
            println!();
        }
        println!("no receiver: the standing teammate nearest the heading, by distance from the ball (rows) and angle off the heading (columns, rad), % of those ticks");
        let none: u64 = self.nearest.iter().flatten().sum::<u64>() + self.all_down;
        print!("  {:>9}", "");
        for c in 0..ANGLE_COLS {
            let lo = c as f32 * ANGLE_STEP;
            if c + 1 == ANGLE_COLS {
                print!(" {:>9}", format!(">={lo:.1}"));
            } else {
                print!(" {:>9}", format!("{lo:.1}-{:.1}", lo + ANGLE_STEP));
            }
        }
        println!();
        for (r, label) in common::bin_labels(&DIST_ROWS).iter().enumerate() {
            print!("  {label:>9}");
            for c in 0..ANGLE_COLS {
                print!(" {:>8.1}%", pct(self.nearest[r][c], none));
            }
            println!();
        }
        println!("  every teammate down: {:.1}%", pct(self.all_down, none));
    }
}

fn main() -> ExitCode {
    let (team, opponent, matches) = match common::team_opponent_matches("pass_chances") {
        Ok(a) => a,
        Err(code) => return code,
    };
    let cfg = MatchConfig::default();
    let reach = match common::sides(&team, &opponent) {
        Ok((Side::Learned(p), _)) => p.scale().kick,
        Ok((Side::Builtin(_), _)) => KickReach::default(),
        Err(code) => return code,
    };
    let mut tally = Tally::default();
    for seed in 1..=matches {
        // The observations the actions of the next tick answer.
        let mut before: Option<[Observation; PLAYERS_PER_TEAM]> = None;
        // Per robot of the team: whether its latest kicking action
        // (`shoot` or `pass`) was `pass`.
        let mut kicked_by_pass = [false; PLAYERS_PER_TEAM];
        let played = common::play_match(&cfg, &team, &opponent, seed, |t| {
            if let Some(obs) = &before {
                for (p, o) in obs.iter().enumerate() {
                    if o.set_play.is_none() && reach.in_reach(o) {
                        tally.count(o, t.actions[p]);
                    }
                }
            }
            for (p, a) in t.actions[..PLAYERS_PER_TEAM].iter().enumerate() {
                match a {
                    Action::Pass => kicked_by_pass[p] = true,
                    Action::Shoot => kicked_by_pass[p] = false,
                    _ => {}
                }
            }
            for e in t.events {
                if let Event::Pass { from, distance, .. } = e {
                    if from.team() == Team::Blue {
                        tally.pass_event(kicked_by_pass[from.player()], *distance);
                    }
                }
            }
            before = Some(std::array::from_fn(|p| t.m.observe(Team::Blue, p)));
            ControlFlow::Continue(())
        });
        if let Err(code) = played {
            return code;
        }
    }
    println!("{team} (blue) against {opponent}, {matches} matches");
    tally.print(matches);
    ExitCode::SUCCESS
}
