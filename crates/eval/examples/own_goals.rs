//! How a team puts the ball into its own goal: for every own goal of the
//! team (a `goal` event of the opponent with phase `own_goal`), the scene
//! of the last three seconds before it, from the match state, one line
//! each:
//!
//! - `kick`: one of the team's robots kicked in those three seconds (its
//!   last kick, how long before the goal);
//! - `walk` or `fall`: the team's last touch, the latest tick with one of
//!   its robots within 0.22 m of the ball (centre to centre), standing or
//!   lying: the robot, how long before the goal, its action then, its
//!   distance from the ball, whether it faced its own goal line (heading
//!   pointing toward it by more than 0.2 of its length), whether the
//!   own-goal guard ([`naosoccer_policy::OwnGoalGuard`], `train
//!   --own-goal-guard`) held for it at any tick of the three seconds, the
//!   ball's x (the own goal line is at -3 on the default pitch) and the
//!   nearest opponent's distance from the ball;
//! - `roll`: no robot of the team that near the ball in those three
//!   seconds.
//!
//! A summary counts the kinds, a match.
//!
//! ```sh
//! cargo run --release -p naosoccer-eval --example own_goals -- \
//!     ppo:assets/policies/ppo-team-seed2 scripted 20
//! ```
//!
//! The team plays blue in every match; match seeds are 1, 2, ... N.

mod common;

use std::collections::VecDeque;
use std::ops::ControlFlow;
use std::process::ExitCode;

use naosoccer_policy::OwnGoalGuard;
use naosoccer_proto::{Action, Event, GoalPhase, Team, PLAYERS_PER_TEAM};
use naosoccer_referee::MatchConfig;

/// Ticks of the scene kept before a goal (3 s at the default 10 Hz).
const SCENE_TICKS: usize = 30;
/// A robot this near the ball (centre to centre, m) touches it: the
/// ball's radius and the robot's feet.
const CONTACT_METRES: f32 = 0.22;

/// One tick of the scene, the team's side of it.
#[derive(Clone, Copy)]
struct Frame {
    ball: [f32; 2],
    /// Per robot of the team: distance from the ball, heading's cosine,
    /// fallen, action, whether the guard held for it.
    robots: [(f32, f32, bool, Action, bool); PLAYERS_PER_TEAM],
    /// The nearest opponent's distance from the ball.
    opponent: f32,
}

#[derive(Default)]
struct Tally {
    kick: u64,
    fall: u64,
    walk: u64,
    walk_facing: u64,
    walk_guarded: u64,
    walk_forward: u64,
    walk_turn: u64,
    rolled: u64,
}

fn main() -> ExitCode {
    let (team, opponent, matches) = match common::team_opponent_matches("own_goals") {
        Ok(a) => a,
        Err(code) => return code,
    };
    let cfg = MatchConfig::default();
    let guard = OwnGoalGuard::for_pitch(cfg.sim.field_length, cfg.sim.goal_width);
    let hz = f64::from(cfg.control_hz);
    let mut tally = Tally::default();
    let mut goals_against = 0u64;
    println!(
        "{:>5} {:>6} {:>5} {:>6} {:>7} {:>8} {:>7} {:>7} {:>7} {:>7} {:>9}",
        "match",
        "minute",
        "kind",
        "robot",
        "ago s",
        "action",
        "dist m",
        "facing",
        "guard",
        "ball x",
        "opp dist"
    );
    for seed in 1..=matches {
        let mut scene: VecDeque<Frame> = VecDeque::with_capacity(SCENE_TICKS + 1);
        // The team's last kick: (tick, robot).
        let mut last_kick: Option<(u64, usize)> = None;
        let played = common::play_match(&cfg, &team, &opponent, seed, |t| {
            let now = t.m.tick().get();
            let first_obs = t.m.observe(Team::Blue, 0);
            let b = first_obs.ball;
            let frame = Frame {
                ball: [b.x, b.y],
                robots: std::array::from_fn(|p| {
                    let o = t.m.observe(Team::Blue, p);
                    let me = o.own[p];
                    (
                        (me.x - b.x).hypot(me.y - b.y),
                        me.heading.cos(),
                        me.fallen,
                        t.actions[p],
                        guard.banned(&o) != 0,
                    )
                }),
                opponent: first_obs
                    .opponents
                    .iter()
                    .map(|r| (r.x - b.x).hypot(r.y - b.y))
                    .fold(f32::INFINITY, f32::min),
            };
            if scene.len() == SCENE_TICKS {
                scene.pop_front();
            }
            scene.push_back(frame);
            for e in t.events {
                match e {
                    Event::Kick { robot, .. } if robot.team() == Team::Blue => {
                        last_kick = Some((now, robot.player()));
                    }
                    Event::Goal { team, .. } if *team != Team::Blue => goals_against += 1,
                    _ => {}
                }
                let Event::Goal {
                    team: Team::Red,
                    phase: Some(GoalPhase::OwnGoal),
                    ..
                } = e
                else {
                    continue;
                };
                let minute = now as f64 / hz / 60.0;
                // The scene before the goal's tick (the ball is already
                // reset in this one).
                let before: Vec<&Frame> = scene.iter().rev().skip(1).collect();
                let ball_x = before.first().map_or(f32::NAN, |f| f.ball[0]);
                if let Some((k, p)) = last_kick.filter(|(k, _)| now - k <= SCENE_TICKS as u64) {
                    tally.kick += 1;
                    println!(
                            "{seed:>5} {minute:>6.2} {:>5} {p:>6} {:>7.1} {:>8} {:>7} {:>7} {:>7} {ball_x:>7.2} {:>9.2}",
                            "kick",
                            (now - k) as f64 / hz,
                            "-",
                            "-",
                            "-",
                            "-",
                            before.first().map_or(f32::NAN, |f| f.opponent)
                        );
                    continue;
                }
                // The team's last contact: the latest tick with one of
                // its robots within touching distance of the ball.
                let contact = before.iter().enumerate().find_map(|(i, f)| {
                    let (p, r) = f
                        .robots
                        .iter()
                        .enumerate()
                        .min_by(|a, b| a.1 .0.total_cmp(&b.1 .0))?;
                    (r.0 < CONTACT_METRES).then_some((i, p))
                });
                let Some((i, p)) = contact else {
                    tally.rolled += 1;
                    println!(
                            "{seed:>5} {minute:>6.2} {:>5} {:>6} {:>7} {:>8} {:>7} {:>7} {:>7} {ball_x:>7.2} {:>9}",
                            "roll", "-", ">3.0", "-", "-", "-", "-", "-"
                        );
                    continue;
                };
                let f = before[i];
                let r = f.robots[p];
                let dist = r.0;
                let facing = r.1 < -0.2;
                let guarded = before.iter().any(|f| f.robots[p].4);
                let kind = if r.2 { "fall" } else { "walk" };
                if r.2 {
                    tally.fall += 1;
                } else {
                    tally.walk += 1;
                    tally.walk_facing += u64::from(facing);
                    tally.walk_guarded += u64::from(guarded);
                    match r.3 {
                        Action::Forward => tally.walk_forward += 1,
                        Action::TurnLeft | Action::TurnRight => tally.walk_turn += 1,
                        _ => {}
                    }
                }
                println!(
                        "{seed:>5} {minute:>6.2} {kind:>5} {p:>6} {:>7.1} {:>8} {dist:>7.2} {:>7} {:>7} {:>7.2} {:>9.2}",
                        (i + 1) as f64 / hz,
                        format!("{:?}", r.3),
                        if facing { "yes" } else { "no" },
                        if guarded { "yes" } else { "no" },
                        f.ball[0],
                        f.opponent
                    );
            }
            ControlFlow::Continue(())
        });
        if let Err(code) = played {
            return code;
        }
    }
    let own = tally.kick + tally.fall + tally.walk + tally.rolled;
    let per = |k: u64| k as f64 / matches as f64;
    println!(
        "own goals: {:.2} a match ({} of {} goals against, {:.1}%), a match: after a kick of the team {:.2}; touched by a fallen robot {:.2}; by a standing one {:.2} (walking forward {:.2}, turning {:.2}; facing the own goal line {:.2}; the guard holding {:.2}); no touch in the last 3 s {:.2}",
        per(own),
        own,
        goals_against,
        common::pct(own, goals_against),
        per(tally.kick),
        per(tally.fall),
        per(tally.walk),
        per(tally.walk_forward),
        per(tally.walk_turn),
        per(tally.walk_facing),
        per(tally.walk_guarded),
        per(tally.rolled)
    );
    ExitCode::SUCCESS
}
