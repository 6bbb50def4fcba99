//! Where a team's shots are taken from and what becomes of them: every
//! kick of the team's robots that is not a pass swung toward a receiver
//! (the `kick` events with no `receiver`), outside set plays, binned by the
//! ball's distance from the centre of the opponent goal and by whether the
//! kicker's heading pointed into the goal mouth, with what ended each
//! shot: a goal of the team, the ball out of play, the opponent's next
//! touch (a kick by an opponent) or the team's own next kick; and how
//! many had an opponent (standing or fallen) within 0.2 m of the heading's
//! line from the ball to the goal line when they were struck.
//!
//! ```sh
//! cargo run --release -p naosoccer-eval --example shots -- \
//!     ppo:assets/policies/ppo-team-seed1 scripted 20
//! ```
//!
//! The team plays blue in every match; match seeds are 1, 2, ... N.

mod common;

use std::ops::ControlFlow;
use std::process::ExitCode;

use common::pct;
use naosoccer_proto::{Event, Observation, Team, PLAYERS_PER_TEAM};
use naosoccer_referee::MatchConfig;

/// An opponent this near the shot's line (m) stands in its way.
const LANE_METRES: f32 = 0.2;

/// Distance rows (upper bounds, m from the centre of the opponent goal).
const DIST_ROWS: [f32; 5] = [1.0, 2.0, 3.0, 4.5, f32::INFINITY];

/// What ended a shot.
#[derive(Clone, Copy)]
enum Outcome {
    Goal,
    Out,
    Opponent,
    Own,
}

/// A shot waiting for its outcome: its row and whether it was aimed.
#[derive(Clone, Copy)]
struct Open {
    row: usize,
    on_target: bool,
    blocked: bool,
}

#[derive(Default)]
struct Tally {
    /// [distance row][heading into the goal mouth][goal, out, opponent, own]
    shots: [[[u64; 4]; 2]; DIST_ROWS.len()],
    /// [distance row][heading into the goal mouth]: shots with an
    /// opponent in the lane.
    blocked: [[u64; 2]; DIST_ROWS.len()],
    /// Shots still open when their match ended.
    unresolved: u64,
}

impl Tally {
    fn close(&mut self, open: &mut Option<Open>, outcome: Outcome) {
        if let Some(s) = open.take() {
            self.shots[s.row][s.on_target as usize][outcome as usize] += 1;
            self.blocked[s.row][s.on_target as usize] += u64::from(s.blocked);
        }
    }

    fn print(&self, matches: u64) {
        let per = |k: u64| k as f64 / matches as f64;
        let all: u64 = self.shots.iter().flatten().flatten().sum();
        let goals: u64 = self.shots.iter().flatten().map(|o| o[0]).sum();
        println!(
            "shots: {:.2} a match, goals from them {:.2} ({:.1}% of shots); {} still rolling at a match's end",
            per(all),
            per(goals),
            pct(goals, all),
            self.unresolved
        );
        println!(
            "  {:>12} {:>8} {:>10} {:>9} {:>7} {:>7} {:>9} {:>7} {:>10}",
            "distance",
            "aimed",
            "shots/m",
            "% shots",
            "goal %",
            "out %",
            "lost %",
            "own %",
            "blocked %"
        );
        for (r, label) in common::bin_labels(&DIST_ROWS).iter().enumerate() {
            for aimed in [1, 0] {
                let o = self.shots[r][aimed];
                let n: u64 = o.iter().sum();
                println!(
                    "  {label:>12} {:>8} {:>10.2} {:>8.1}% {:>6.1}% {:>6.1}% {:>8.1}% {:>6.1}% {:>9.1}%",
                    if aimed == 1 { "yes" } else { "no" },
                    per(n),
                    pct(n, all),
                    pct(o[0], n),
                    pct(o[1], n),
                    pct(o[2], n),
                    pct(o[3], n),
                    pct(self.blocked[r][aimed], n)
                );
            }
        }
    }
}

fn main() -> ExitCode {
    let (team, opponent, matches) = match common::team_opponent_matches("shots") {
        Ok(a) => a,
        Err(code) => return code,
    };
    let cfg = MatchConfig::default();
    let goal_x = cfg.sim.field_length / 2.0;
    let half_mouth = cfg.sim.goal_width / 2.0;
    let mut tally = Tally::default();
    for seed in 1..=matches {
        // The team's observations of the tick before: a kick event's
        // kicker saw the ball there.
        let mut before: Option<[Observation; PLAYERS_PER_TEAM]> = None;
        let mut open: Option<Open> = None;
        let played = common::play_match(&cfg, &team, &opponent, seed, |t| {
            for e in t.events {
                match e {
                    Event::Goal { team, .. } => {
                        if *team == Team::Blue {
                            tally.close(&mut open, Outcome::Goal);
                        } else {
                            open = None;
                        }
                    }
                    Event::BallOut { .. } => tally.close(&mut open, Outcome::Out),
                    Event::Kick {
                        robot, receiver, ..
                    } => {
                        if robot.team() != Team::Blue {
                            tally.close(&mut open, Outcome::Opponent);
                            continue;
                        }
                        tally.close(&mut open, Outcome::Own);
                        let Some(obs) = before.as_ref().map(|o| &o[robot.player()]) else {
                            continue;
                        };
                        if receiver.is_some() || obs.set_play.is_some() {
                            continue;
                        }
                        let (bx, by) = (obs.ball.x, obs.ball.y);
                        let d = (goal_x - bx).hypot(by);
                        let row = DIST_ROWS.iter().position(|&m| d < m).unwrap_or(0);
                        let h = obs.own[robot.player()].heading;
                        // Where the heading's line from the ball meets the
                        // goal line, if it points at it.
                        let on_target = h.cos() > 1e-3 && {
                            let y = by + (goal_x - bx) * h.tan();
                            y.abs() < half_mouth
                        };
                        // The heading's segment from the ball to the goal
                        // line (or 6 m along it when it points away).
                        let (c, sn) = (h.cos(), h.sin());
                        let len = if c > 1e-3 {
                            ((goal_x - bx) / c).clamp(0.0, 6.0)
                        } else {
                            6.0
                        };
                        let blocked = obs.opponents.iter().any(|r| {
                            let (dx, dy) = (r.x - bx, r.y - by);
                            let along = (dx * c + dy * sn).clamp(0.0, len);
                            (dx - along * c).hypot(dy - along * sn) < LANE_METRES
                        });
                        open = Some(Open {
                            row,
                            on_target,
                            blocked,
                        });
                    }
                    _ => {}
                }
            }
            before = Some(std::array::from_fn(|p| t.m.observe(Team::Blue, p)));
            ControlFlow::Continue(())
        });
        if let Err(code) = played {
            return code;
        }
        tally.unresolved += u64::from(open.is_some());
    }
    println!("{team} (blue) against {opponent}, {matches} matches");
    tally.print(matches);
    ExitCode::SUCCESS
}
