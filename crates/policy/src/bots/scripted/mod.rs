//! The paper's rule-based team (section II.A), over the observation only.
//!
//! Every field player computes the same role assignment from the same
//! observation: the teammate closest to the ball (or the one controlling it)
//! engages, the other two take support places. Engaging follows the paper:
//! face the ball (turn while the heading deviation `dtheta` exceeds `b_rad`),
//! approach with `forward`, take control, and `shoot` when the distance
//! condition (ball near the opponent goal, within the goal's width) and the
//! angle condition (robot, ball and goal centre nearly on one line,
//! `|dtheta_target| < b_shoot`) both hold; otherwise dribble on, or first walk
//! round behind the ball so that the line to goal opens. With the ball at its
//! feet a player also passes to a teammate ahead in its line of fire and
//! clears from its own half. Player 0 keeps goal: it stays on its line
//! following the ball, and only engages when the ball enters its zone.
//!
//! The only memory is per robot (turning hysteresis), so one instance per
//! robot, as the server and runner build them, is deterministic.

use naosoccer_proto::{
    pass_receiver, Action, Observation, RobotObs, SetPlayKind, PLAYERS_PER_TEAM,
};

use super::Policy;

mod geometry;
mod params;
use geometry::{add, around, cross, dist, dot, local, norm, scale, sub, turn_towards, wrap};
pub use params::{ScriptedParams, DEFAULT_LEVEL, LEVELS};

/// One robot's scripted player.
#[derive(Debug, Clone)]
pub struct Scripted {
    p: ScriptedParams,
    /// Turning towards a target until the error is small (hysteresis).
    turning: bool,
    /// Heading when the last turn was asked for: a robot wedged between
    /// others turns without its heading changing.
    turned_from: Option<f32>,
    /// Ticks in a row a turn did not move the heading.
    stuck: u32,
    /// Ticks left walking out of a jam.
    escape: u32,
    /// The last action decided, held between decisions (`react_ticks`).
    last: Action,
}

/// Ticks of turning without effect before a player walks out of a jam.
const STUCK_TICKS: u32 = 20;
/// Ticks it then walks.
const ESCAPE_TICKS: u32 = 8;

impl Scripted {
    pub fn new(p: ScriptedParams) -> Scripted {
        Scripted {
            p,
            turning: false,
            turned_from: None,
            stuck: 0,
            escape: 0,
            last: Action::Stay,
        }
    }

    fn decide(&mut self, obs: &Observation) -> Action {
        if self.p.set_play_guard > 0.0
            && obs.player.index() != 0
            && obs.set_play.is_some_and(|sp| !sp.own)
            && (guard_rank(obs) as f32) < self.p.set_play_guard
        {
            return self.guard_set_play(obs);
        }
        if obs.player.index() == 0 {
            self.keeper(obs)
        } else {
            self.field_player(obs)
        }
    }

    fn keeper(&mut self, obs: &Observation) -> Action {
        let p = &self.p;
        let me = obs.me();
        let own_line = -p.half_length;
        let now = [obs.ball.x, obs.ball.y];
        if now[0] < own_line + p.keeper_zone && now[1].abs() < p.goal_half_width + 0.6 {
            return self.engage(obs, true);
        }
        let ball = self.team_ball(obs);
        let home = if p.keeper_guard > 0.0 {
            // On the line from the goal centre to the ball.
            let goal = [own_line, 0.0];
            let to = sub(ball, goal);
            let u = scale(to, 1.0 / norm(to).max(1e-6));
            let spot = add(goal, scale(u, p.keeper_guard));
            [spot[0].max(own_line + 0.15), spot[1]]
        } else {
            [own_line + 0.35, (ball[1] * 0.4).clamp(-0.7, 0.7)]
        };
        if dist([me.x, me.y], home) > p.arrive {
            self.go_to(me, home)
        } else {
            self.face(me, ball)
        }
    }

    fn field_player(&mut self, obs: &Observation) -> Action {
        let me_idx = obs.player.index();
        let ball = self.team_ball(obs);
        let engager = if self.p.engage_path > 0.0 || self.p.engage_turn > 0.0 {
            self.engager_by_way(obs, ball)
        } else {
            engager(obs, ball)
        };
        if engager == Some(me_idx) {
            return self.engage(obs, false);
        }
        // Support places, by rank among the non-engaging field players.
        let rank = (1..PLAYERS_PER_TEAM)
            .filter(|&i| Some(i) != engager && i < me_idx)
            .count();
        let side = if ball[1] >= 0.0 { -1.0 } else { 1.0 };
        let hl = self.p.half_length;
        // The covering player (rank 1) marks first, then the support player.
        let marked = 1usize
            .checked_sub(rank)
            .filter(|&k| (k as f32) < self.p.markers)
            .and_then(|k| self.mark_spot(obs, k));
        let spot = if let Some(spot) = marked {
            spot
        } else if rank == 0 {
            // Ahead of the ball, across from it: a pass or a rebound comes here.
            [
                (ball[0] + self.p.support_ahead).clamp(-1.5, hl - 0.7),
                (ball[1] + side * 0.7).clamp(-1.6, 1.6),
            ]
        } else {
            // Behind the ball, covering the middle.
            [
                (ball[0] - self.p.cover_behind).clamp(-hl + 1.0, self.p.cover_max_x.max(-hl + 1.0)),
                (ball[1] * 0.5).clamp(-1.2, 1.2),
            ]
        };
        let me = obs.me();
        if dist([me.x, me.y], spot) > self.p.arrive {
            self.go_to(me, spot)
        } else {
            self.face(me, ball)
        }
    }

    /// Go for the ball and play it towards the opponent goal.
    fn engage(&mut self, obs: &Observation, keeper: bool) -> Action {
        let p = self.p;
        let me = obs.me();
        let pos = [me.x, me.y];
        // Where the ball is, for the kick; where it will be when this
        // player gets there, for the walk (`lead`; the same without it).
        let now = [obs.ball.x, obs.ball.y];
        let ball = self.my_ball(obs);
        let goal = [p.half_length, self.aim_y(obs)];
        let to_goal = sub(goal, ball);
        let line = to_goal[1].atan2(to_goal[0]);
        let to_ball = sub(ball, pos);
        let d = norm(to_ball);
        let ball_dir = to_ball[1].atan2(to_ball[0]);
        // The paper's dtheta (heading to ball) and dtheta_target (robot, ball, goal alignment).
        let dtheta = wrap(ball_dir - me.heading);
        let dtheta_target = wrap(ball_dir - line);

        if dtheta_target.abs() < p.align_tolerance
            || (d < 0.25 && dtheta_target.abs() < 2.0 * p.align_tolerance)
        {
            let (fwd, lat) = local(me, now);
            let in_reach =
                fwd >= p.reach_min && fwd <= p.reach_max && lat.abs() <= p.reach_half_width;
            if in_reach {
                let distance_ok =
                    now[0] > p.half_length - p.shoot_range && now[1].abs() < p.goal_half_width;
                let shot =
                    (distance_ok && dtheta_target.abs() < p.b_shoot) || self.on_target(me, now);
                if let Some(sp) = obs.set_play.filter(|sp| sp.own && p.set_play_pass > 0.0) {
                    // A kick-off goal counts only after another robot's touch.
                    let direct = sp.kind != SetPlayKind::KickOff && shot;
                    if !direct {
                        if pass_receiver(obs).is_some() {
                            return Action::Pass;
                        }
                        if sp.ticks_left as f32 > p.set_play_wait {
                            return Action::Stay;
                        }
                    }
                }
                if shot {
                    return Action::Shoot;
                }
                if p.aimed_pass > 0.0 {
                    // The protocol's pass: a kick at the receiver's feet.
                    let ahead = pass_receiver(obs).is_some_and(|j| obs.own[j].x > now[0] + 0.3);
                    if ahead {
                        return Action::Pass;
                    }
                } else if self.pass_open(obs) {
                    return Action::Shoot;
                }
                // Challenged: kick it on rather than push against the opponent.
                let contested = obs
                    .opponents
                    .iter()
                    .any(|o| !o.fallen && dist([o.x, o.y], now) < p.contest_radius);
                if contested && wrap(me.heading).abs() < std::f32::consts::FRAC_PI_2 {
                    return Action::Shoot;
                }
                // Clear the ball out of the own half, roughly forwards.
                let clear_cone = if keeper { 0.9 } else { 0.5 };
                if now[0] < p.clear_x && wrap(me.heading).abs() < clear_cone {
                    return Action::Shoot;
                }
            }
            if dtheta.abs() > p.b_rad || (self.turning && dtheta.abs() > p.turn_stop) {
                self.turning = true;
                return turn_towards(dtheta);
            }
            self.turning = false;
            return Action::Forward;
        }

        // Walk round behind the ball; go wide when the ball is in the way.
        let u = scale(to_goal, 1.0 / norm(to_goal).max(1e-6));
        let target = round_the_ball(&p, pos, ball, u).unwrap_or(sub(ball, scale(u, p.behind)));
        self.go_to(me, target)
    }

    /// The field player that goes for the ball (`engage_path`,
    /// `engage_turn`): the one in control, else the standing one with the
    /// shortest way to a kick toward the goal (lower number on a tie).
    fn engager_by_way(&self, obs: &Observation, ball: [f32; 2]) -> Option<usize> {
        if let Some(i) = (1..PLAYERS_PER_TEAM).find(|&i| obs.control[i]) {
            return Some(i);
        }
        (1..PLAYERS_PER_TEAM)
            .filter(|&i| !obs.own[i].fallen)
            .map(|i| (self.way_to_kick(obs, &obs.own[i], ball), i))
            .fold(None, |best: Option<(f32, usize)>, c| match best {
                Some(b) if b.0 <= c.0 => Some(b),
                _ => Some(c),
            })
            .map(|(_, i)| i)
    }

    /// How far `r` has to go to kick `ball` toward the goal: straight to
    /// it when it is lined up (as `engage` decides), else round behind it;
    /// mixed with the straight distance by `engage_path`, plus
    /// `engage_turn` per radian of turning toward its first waypoint.
    fn way_to_kick(&self, obs: &Observation, r: &RobotObs, ball: [f32; 2]) -> f32 {
        let p = &self.p;
        let pos = [r.x, r.y];
        let goal = [p.half_length, self.aim_y(obs)];
        let to_goal = sub(goal, ball);
        let u = scale(to_goal, 1.0 / norm(to_goal).max(1e-6));
        let to_ball = sub(ball, pos);
        let d = norm(to_ball);
        let ball_dir = to_ball[1].atan2(to_ball[0]);
        let line = to_goal[1].atan2(to_goal[0]);
        let lined_up = wrap(ball_dir - line).abs();
        let (path, first) =
            if lined_up < p.align_tolerance || (d < 0.25 && lined_up < 2.0 * p.align_tolerance) {
                (d, ball)
            } else {
                let behind = sub(ball, scale(u, p.behind));
                match round_the_ball(p, pos, ball, u) {
                    // The ball is in the way: round it first.
                    Some(wide) => (dist(pos, wide) + dist(wide, behind) + p.behind, wide),
                    None => (dist(pos, behind) + p.behind, behind),
                }
            };
        let to_first = sub(first, pos);
        let turn = wrap(to_first[1].atan2(to_first[0]) - r.heading).abs();
        d + p.engage_path * (path - d) + p.engage_turn * turn
    }

    /// Where the ball will be `t` seconds from now if nothing touches it:
    /// its speed decays as exp(-`ball_damping` t); not past a goal line.
    fn ball_in(&self, obs: &Observation, t: f32) -> [f32; 2] {
        let k = self.p.ball_damping;
        let f = (1.0 - (-k * t).exp()) / k;
        let hl = self.p.half_length;
        [
            (obs.ball.x + obs.ball.vx * f).clamp(-hl, hl),
            obs.ball.y + obs.ball.vy * f,
        ]
    }

    /// The ball as the team reads it (`lead` seconds ahead; where it is
    /// without `lead`): who goes for it, the support places, the keeper's
    /// place.
    fn team_ball(&self, obs: &Observation) -> [f32; 2] {
        if self.p.lead > 0.0 {
            self.ball_in(obs, self.p.lead)
        } else {
            [obs.ball.x, obs.ball.y]
        }
    }

    /// The ball as the player going for it reads it: where it will be when
    /// the player, walking at `walk_speed`, can be there (at most `lead`
    /// seconds ahead; a fixed point of three rounds).
    fn my_ball(&self, obs: &Observation) -> [f32; 2] {
        let now = [obs.ball.x, obs.ball.y];
        if self.p.lead <= 0.0 {
            return now;
        }
        let me = obs.me();
        let mut at = now;
        for _ in 0..3 {
            let t = (dist([me.x, me.y], at) / self.p.walk_speed).min(self.p.lead);
            at = self.ball_in(obs, t);
        }
        at
    }

    /// Whether a kick along the heading from `ball` goes in (`shot_line`):
    /// the ball within `shot_line` of the opponent goal centre and the
    /// heading's line crossing the goal line `shot_margin` inside the posts.
    fn on_target(&self, me: &RobotObs, ball: [f32; 2]) -> bool {
        let p = &self.p;
        if p.shot_line <= 0.0 || dist(ball, [p.half_length, 0.0]) > p.shot_line {
            return false;
        }
        let (s, c) = me.heading.sin_cos();
        if c <= 0.05 {
            return false;
        }
        let y = ball[1] + (p.half_length - ball[0]) / c * s;
        y.abs() < p.goal_half_width - p.shot_margin
    }

    /// Where shots aim across the goal mouth: the centre, or `aim_offset`
    /// toward the post farther from the opponent nearest the goal centre
    /// (their keeper, as far as the observation tells).
    fn aim_y(&self, obs: &Observation) -> f32 {
        if self.p.aim_offset <= 0.0 {
            return 0.0;
        }
        let goal = [self.p.half_length, 0.0];
        let keeper = obs
            .opponents
            .iter()
            .filter(|o| !o.fallen)
            .map(|o| (dist([o.x, o.y], goal), o.y))
            .fold(None, |best: Option<(f32, f32)>, c| match best {
                Some(b) if b.0 <= c.0 => Some(b),
                _ => Some(c),
            });
        match keeper {
            Some((_, y)) if y >= 0.0 => -self.p.aim_offset,
            _ => self.p.aim_offset,
        }
    }

    /// The place of the `k`-th marker (0: the first): `mark_gap` goal-side
    /// of the `k`-th opponent nearest the own goal, leaving out the one
    /// nearest the ball, fallen ones and those beyond `mark_range`.
    fn mark_spot(&self, obs: &Observation, k: usize) -> Option<[f32; 2]> {
        let p = &self.p;
        let ball = [obs.ball.x, obs.ball.y];
        let goal = [-p.half_length, 0.0];
        let at_ball = nearest(&obs.opponents, ball);
        let mut targets: Vec<(f32, usize)> = (0..PLAYERS_PER_TEAM)
            .filter(|&i| Some(i) != at_ball && !obs.opponents[i].fallen)
            .map(|i| (dist([obs.opponents[i].x, obs.opponents[i].y], goal), i))
            .filter(|&(d, _)| d <= p.mark_range)
            .collect();
        targets.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        let (_, i) = *targets.get(k)?;
        let o = [obs.opponents[i].x, obs.opponents[i].y];
        let to = sub(goal, o);
        Some(add(o, scale(to, p.mark_gap / norm(to).max(1e-6))))
    }

    /// At the other team's set play: the field player nearest the ball
    /// blocks the line from the ball to the own goal, the others the lanes
    /// to the two likeliest receivers, all just outside the keep-out circle.
    fn guard_set_play(&mut self, obs: &Observation) -> Action {
        let p = self.p;
        let me = obs.me();
        let pos = [me.x, me.y];
        let ball = [obs.ball.x, obs.ball.y];
        let goal = [-p.half_length, 0.0];
        let by_ball = |robots: &[RobotObs], skip: &dyn Fn(usize) -> bool| {
            let mut v: Vec<(f32, usize)> = (0..PLAYERS_PER_TEAM)
                .filter(|&i| !skip(i) && !robots[i].fallen)
                .map(|i| (dist([robots[i].x, robots[i].y], ball), i))
                .collect();
            v.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
            v.into_iter().map(|(_, i)| i).collect::<Vec<_>>()
        };
        let rank = guard_rank(obs);
        let spot = if rank == 0 {
            let to = sub(goal, ball);
            add(ball, scale(to, p.keep_out / norm(to).max(1e-6)))
        } else {
            // The taker is the opponent nearest the ball.
            let receivers = by_ball(&obs.opponents, &|_| false);
            match receivers.get(rank) {
                Some(&j) => {
                    let r = [obs.opponents[j].x, obs.opponents[j].y];
                    let lane = sub(r, ball);
                    let len = norm(lane);
                    if len > p.keep_out + p.mark_gap {
                        add(ball, scale(lane, p.keep_out / len))
                    } else {
                        let to = sub(goal, r);
                        add(r, scale(to, p.mark_gap / norm(to).max(1e-6)))
                    }
                }
                None => {
                    let to = sub(goal, ball);
                    add(ball, scale(to, (p.keep_out + 1.0) / norm(to).max(1e-6)))
                }
            }
        };
        if dist(pos, spot) > p.arrive {
            let waypoint = around(ball, pos, spot, 0.9 * p.keep_out);
            self.go_to(me, waypoint)
        } else {
            self.face(me, ball)
        }
    }

    /// A teammate ahead in the line of fire, with no opponent near the lane.
    fn pass_open(&self, obs: &Observation) -> bool {
        let p = &self.p;
        let me = obs.me();
        let ball = [obs.ball.x, obs.ball.y];
        obs.own.iter().enumerate().any(|(i, t)| {
            if i == obs.player.index() || t.fallen || t.x < ball[0] + 0.3 {
                return false;
            }
            let lane = sub([t.x, t.y], ball);
            let len = norm(lane);
            if !(0.8..=p.pass_range).contains(&len) {
                return false;
            }
            if wrap(lane[1].atan2(lane[0]) - me.heading).abs() > p.pass_cone {
                return false;
            }
            let u = scale(lane, 1.0 / len);
            !obs.opponents.iter().any(|o| {
                let rel = sub([o.x, o.y], ball);
                let along = dot(rel, u);
                along > 0.0 && along < len && cross(u, rel).abs() < 0.4
            })
        })
    }

    fn go_to(&mut self, me: &RobotObs, target: [f32; 2]) -> Action {
        let to = sub(target, [me.x, me.y]);
        let err = wrap(to[1].atan2(to[0]) - me.heading);
        if self.steer(err) {
            turn_towards(err)
        } else {
            Action::Forward
        }
    }

    fn face(&mut self, me: &RobotObs, target: [f32; 2]) -> Action {
        let to = sub(target, [me.x, me.y]);
        let err = wrap(to[1].atan2(to[0]) - me.heading);
        if self.steer(err) {
            turn_towards(err)
        } else {
            Action::Stay
        }
    }

    /// Whether to turn now: start above `turn_start`, keep on until below `turn_stop`.
    fn steer(&mut self, err: f32) -> bool {
        let e = err.abs();
        self.turning = if self.turning {
            e > self.p.turn_stop
        } else {
            e > self.p.turn_start
        };
        self.turning
    }
}

impl Policy for Scripted {
    fn act(&mut self, obs: &Observation) -> Action {
        let heading = obs.me().heading;
        if obs.me().fallen {
            self.turning = false;
            self.turned_from = None;
            self.stuck = 0;
            self.escape = 0;
            self.last = Action::Stay;
            return Action::Stay;
        }
        if self.p.react_ticks > 1.0 {
            let k = self.p.react_ticks as u64;
            // (Not `is_multiple_of`: the library crates keep Rust 1.86.)
            let phase = (obs.tick.get() + obs.player.index() as u64) % k;
            let turning = matches!(self.last, Action::TurnLeft | Action::TurnRight);
            if phase != 0 && (self.p.hold_turns > 0.0 || !turning) {
                return self.last;
            }
        }
        if let Some(from) = self.turned_from.take() {
            if wrap(heading - from).abs() < 0.01 {
                self.stuck += 1;
            } else {
                self.stuck = 0;
            }
        } else {
            self.stuck = 0;
        }
        if self.stuck >= STUCK_TICKS {
            self.stuck = 0;
            self.escape = ESCAPE_TICKS;
            self.turning = false;
        }
        if self.escape > 0 {
            self.escape -= 1;
            self.last = Action::Forward;
            return Action::Forward;
        }
        let action = self.decide(obs);
        if matches!(action, Action::TurnLeft | Action::TurnRight) {
            self.turned_from = Some(heading);
        }
        self.last = action;
        action
    }

    fn name(&self) -> &str {
        "scripted"
    }
}

/// A field player's rank by distance to the ball among its standing
/// teammates other than the keeper (0: the nearest; lower number on a tie),
/// as the guards of the other team's set play are chosen.
fn guard_rank(obs: &Observation) -> usize {
    let ball = [obs.ball.x, obs.ball.y];
    let mut v: Vec<(f32, usize)> = (1..PLAYERS_PER_TEAM)
        .filter(|&i| !obs.own[i].fallen)
        .map(|i| (dist([obs.own[i].x, obs.own[i].y], ball), i))
        .collect();
    v.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    v.iter()
        .position(|&(_, i)| i == obs.player.index())
        .unwrap_or(0)
}

/// The field player (1..=3) that goes for the ball: the one in control, else
/// the closest standing one to `ball` (lower number on a tie).
fn engager(obs: &Observation, ball: [f32; 2]) -> Option<usize> {
    if let Some(i) = (1..PLAYERS_PER_TEAM).find(|&i| obs.control[i]) {
        return Some(i);
    }
    (1..PLAYERS_PER_TEAM)
        .filter(|&i| !obs.own[i].fallen)
        .map(|i| (dist([obs.own[i].x, obs.own[i].y], ball), i))
        .fold(None, |best: Option<(f32, usize)>, c| match best {
            Some(b) if b.0 <= c.0 => Some(b),
            _ => Some(c),
        })
        .map(|(_, i)| i)
}

/// The robot of `robots` nearest `p` (standing or not; lower number on a tie).
fn nearest(robots: &[RobotObs; PLAYERS_PER_TEAM], p: [f32; 2]) -> Option<usize> {
    (0..PLAYERS_PER_TEAM)
        .map(|i| (dist([robots[i].x, robots[i].y], p), i))
        .fold(None, |best: Option<(f32, usize)>, c| match best {
            Some(b) if b.0 <= c.0 => Some(b),
            _ => Some(c),
        })
        .map(|(_, i)| i)
}

/// Where a player at `pos` walks first when the ball at `ball` is in its
/// way to the line-up point (`u`: the unit vector from the ball toward the
/// goal): it stands less than 0.15 m behind the ball on that line and less
/// than 0.45 m to its side. Then: 0.5 m beside the ball, on the player's
/// side, `wide_behind` behind it. `None` when the ball is not in the way.
fn round_the_ball(
    p: &ScriptedParams,
    pos: [f32; 2],
    ball: [f32; 2],
    u: [f32; 2],
) -> Option<[f32; 2]> {
    let rel = sub(pos, ball);
    let along = dot(rel, u);
    let across = cross(u, rel);
    if along > -0.15 && across.abs() < 0.45 {
        let side = if across >= 0.0 { 1.0 } else { -1.0 };
        let perp = [-u[1] * side, u[0] * side];
        Some(add(ball, add(scale(perp, 0.5), scale(u, -p.wide_behind))))
    } else {
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use naosoccer_proto::Tick;
    use naosoccer_proto::{BallObs, Team};

    /// The wide point of a walk round the ball: on the edge of the region
    /// where the ball is in the way by default (0.15 m behind the ball), so a
    /// player that sways 1 cm on its way to the line-up point is back in
    /// the region and heads for the wide point again; with `wide_behind =
    /// 0.3` the whole way from the wide point to the line-up point keeps
    /// 0.15 m clear of the region.
    #[test]
    fn the_wide_point_lies_on_the_regions_edge_by_default_and_clear_of_it_at_0_3() {
        let ball = [2.4, -1.7];
        let to_goal = sub([3.0, 0.0], ball);
        let u = scale(to_goal, 1.0 / norm(to_goal));
        // A robot as one of the scripted team stood for seconds in a
        // recorded match: 0.03 m behind the ball, 0.43 m to its side.
        let pos = [1.98, -1.58];
        // The smallest distance (m) behind the region's edge (0.15 m behind
        // the ball) along the way from the wide point to the line-up point.
        let clearance = |wide_behind: f32| {
            let p = ScriptedParams {
                wide_behind,
                ..ScriptedParams::default()
            };
            let wide = round_the_ball(&p, pos, ball, u).expect("the ball is in the way");
            let behind = sub(ball, scale(u, p.behind));
            assert!(round_the_ball(&p, behind, ball, u).is_none());
            (0..=100)
                .map(|k| {
                    let t = k as f32 / 100.0;
                    let at = add(wide, scale(sub(behind, wide), t));
                    -dot(sub(at, ball), u) - 0.15
                })
                .fold(f32::INFINITY, f32::min)
        };
        let default = clearance(ScriptedParams::default().wide_behind);
        assert!(default.abs() < 1e-5, "{default}");
        let fixed = clearance(0.3);
        assert!(fixed > 0.149, "{fixed}");
        // The wide point is 0.5 m beside the ball on the robot's side.
        let p = ScriptedParams::default();
        let wide = round_the_ball(&p, pos, ball, u).unwrap();
        assert!((cross(u, sub(wide, ball)) - 0.5).abs() < 1e-5);
        assert!(round_the_ball(&p, [1.5, -1.7], ball, u).is_none());
    }

    fn obs(player: u8, me: RobotObs, ball: [f32; 2]) -> Observation {
        let mut own = [RobotObs {
            x: -2.0,
            y: 2.0,
            heading: 0.0,
            fallen: false,
            busy: false,
        }; PLAYERS_PER_TEAM];
        // Teammates far away so `me` is the engager.
        for (i, r) in own.iter_mut().enumerate() {
            r.y = 2.0 - i as f32 * 0.1;
            r.x = -2.9;
        }
        own[player as usize] = me;
        Observation {
            tick: Tick::ZERO,
            team: Team::Blue,
            player: naosoccer_proto::Player::new(player as usize).unwrap(),
            time_left: 600.0,
            score: Default::default(),
            own,
            opponents: [RobotObs {
                x: 2.5,
                y: -2.0,
                heading: std::f32::consts::PI,
                fallen: false,
                busy: false,
            }; PLAYERS_PER_TEAM],
            ball: BallObs {
                x: ball[0],
                y: ball[1],
                vx: 0.0,
                vy: 0.0,
            },
            control: [false; PLAYERS_PER_TEAM],
            opponent_control: false,
            reward: 0.0,
            half: 1,
            set_play: None,
        }
    }

    fn robot(x: f32, y: f32, heading: f32) -> RobotObs {
        RobotObs {
            x,
            y,
            heading,
            fallen: false,
            busy: false,
        }
    }

    #[test]
    fn turns_to_face_the_ball_then_approaches() {
        let mut s = Scripted::new(ScriptedParams::default());
        // Ball straight ahead towards the goal but the robot looks left.
        let o = obs(1, robot(0.0, 0.0, 1.2), [1.0, 0.0]);
        assert_eq!(s.act(&o), Action::TurnRight);
        let o = obs(1, robot(0.0, 0.0, 0.0), [1.0, 0.0]);
        let mut s = Scripted::new(ScriptedParams::default());
        assert_eq!(s.act(&o), Action::Forward);
    }

    #[test]
    fn shoots_only_when_distance_and_angle_conditions_hold() {
        let mut s = Scripted::new(ScriptedParams::default());
        // In reach, aligned with the goal, close to it.
        let o = obs(1, robot(2.0, 0.0, 0.0), [2.18, 0.0]);
        assert_eq!(s.act(&o), Action::Shoot);
        // Same alignment far from goal in the opponent half: dribble on.
        let o = obs(1, robot(-0.2, 0.0, 0.0), [-0.02, 0.0]);
        assert_eq!(s.act(&o), Action::Forward);
        // Close to goal but robot-ball-goal not aligned: no shot.
        let o = obs(1, robot(2.0, -1.0, 0.0), [2.18, -1.0]);
        assert_ne!(s.act(&o), Action::Shoot);
    }

    #[test]
    fn a_reading_player_walks_to_where_the_rolling_ball_will_be() {
        // The ball 0.6 m straight ahead, rolling across at 1 m/s: it stops
        // about 1.25 m to the left.
        let mut o = obs(1, robot(0.0, 0.0, 0.0), [0.6, 0.0]);
        o.ball.vy = 1.0;
        let mut s = Scripted::new(ScriptedParams::default());
        assert_eq!(s.act(&o), Action::Forward, "without lead: at the ball");
        let reading = ScriptedParams::parse_spec("lead=3").unwrap();
        let mut s = Scripted::new(reading);
        let at = s.my_ball(&o);
        assert!(
            (at[0] - 0.6).abs() < 1e-6 && at[1] > 1.0 && at[1] < 1.25,
            "{at:?}"
        );
        assert_eq!(
            s.act(&o),
            Action::TurnLeft,
            "with lead: toward where it stops"
        );
        // A ball at rest reads the same with or without lead.
        o.ball.vy = 0.0;
        assert_eq!(s.my_ball(&o), [0.6, 0.0]);
        assert_eq!(s.team_ball(&o), [0.6, 0.0]);
    }

    #[test]
    fn a_variant_with_a_longer_range_shoots_where_the_default_dribbles() {
        let o = obs(1, robot(-0.2, 0.0, 0.0), [-0.02, 0.0]);
        let mut s = Scripted::new(ScriptedParams::default());
        assert_eq!(s.act(&o), Action::Forward);
        let far = ScriptedParams::parse_spec("shoot_range=3.5").unwrap();
        assert_eq!(Scripted::new(far).act(&o), Action::Shoot);
    }

    #[test]
    fn the_shipped_variants_parse_and_differ_from_the_default() {
        let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/../../assets/scripted");
        let mut names: Vec<_> = std::fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().path())
            .filter(|p| p.extension().is_some_and(|e| e == "toml"))
            .collect();
        names.sort();
        assert!(names.len() >= 2, "{names:?}");
        for path in names {
            let p = ScriptedParams::parse_spec(path.to_str().unwrap()).unwrap();
            assert_ne!(p, ScriptedParams::default(), "{}", path.display());
        }
    }

    #[test]
    fn the_levels_parse_and_level_3_is_the_scripted_team() {
        let levels: Vec<ScriptedParams> = (1..=LEVELS.len() as u8)
            .map(|n| ScriptedParams::level(n).unwrap())
            .collect();
        assert_eq!(
            levels[usize::from(DEFAULT_LEVEL) - 1],
            ScriptedParams::default()
        );
        for (i, a) in levels.iter().enumerate() {
            for b in &levels[i + 1..] {
                assert_ne!(a, b);
            }
            // A level changes no pitch size.
            let d = ScriptedParams::default();
            assert_eq!(
                (a.half_length, a.goal_half_width, a.b_rad),
                (d.half_length, d.goal_half_width, d.b_rad)
            );
        }
        // The files on disk are the levels built in.
        for (i, text) in LEVELS.iter().enumerate() {
            let path = format!(
                "{}/../../assets/scripted/levels/level-{}.toml",
                env!("CARGO_MANIFEST_DIR"),
                i + 1
            );
            assert_eq!(std::fs::read_to_string(&path).unwrap(), *text, "{path}");
            assert_eq!(ScriptedParams::parse_spec(&path).unwrap(), levels[i]);
        }
        // The first ladder's levels 4 and 5 (which the shipped PPO recipe
        // trains against) are today's without who-goes-for-the-ball and
        // the tighter line-up.
        let v1 = |n: u8| {
            ScriptedParams::parse_spec(&format!(
                "{}/../../assets/scripted/ladder-v1/level-{n}.toml",
                env!("CARGO_MANIFEST_DIR")
            ))
            .unwrap()
        };
        let off = ScriptedParams::default();
        let without = |p: ScriptedParams| ScriptedParams {
            engage_path: off.engage_path,
            engage_turn: off.engage_turn,
            align_tolerance: off.align_tolerance,
            ..p
        };
        assert_eq!(v1(4), without(levels[3]));
        assert_eq!(v1(5), without(levels[4]));
        assert_ne!(v1(4), levels[3]);
        assert_ne!(v1(5), levels[4]);
        let five = ScriptedParams::parse_spec("5,b_shoot=0.3").unwrap();
        assert_eq!(
            five,
            ScriptedParams {
                b_shoot: 0.3,
                ..levels[4]
            }
        );
        assert_eq!(ScriptedParams::parse_spec("2").unwrap(), levels[1]);
        for bad in ["0", "6", "300", "5,", "5,b_shot=1"] {
            assert!(ScriptedParams::parse_spec(bad).is_err(), "{bad}");
        }
        assert!(ScriptedParams::parse_spec("6")
            .unwrap_err()
            .contains("the levels are 1 to 5"));
    }

    /// `engage_path`: the field player with the shortest way to a kick
    /// toward the goal goes for the ball, not the nearest one. Player 1
    /// stands 0.5 m in front of the ball (the opponent goal's side), player
    /// 2 0.8 m behind it, both facing it: player 1 is nearer, but must walk
    /// round the ball first.
    #[test]
    fn the_player_with_the_shorter_way_to_a_kick_goes_for_the_ball() {
        let ball = [0.0, 0.0];
        let mut o = obs(1, robot(0.5, 0.0, std::f32::consts::PI), ball);
        o.own[2] = robot(-0.8, 0.0, 0.0);
        let nearest = Scripted::new(ScriptedParams::default());
        assert_eq!(engager(&o, ball), Some(1));
        assert_eq!(nearest.p.engage_path, 0.0);
        let by_way = Scripted::new(ScriptedParams::parse_spec("engage_path=1").unwrap());
        assert_eq!(by_way.engager_by_way(&o, ball), Some(2));
        // Half the detour counted: 0.5 + (way - 0.5) / 2 is still longer.
        let half = Scripted::new(ScriptedParams::parse_spec("engage_path=0.5").unwrap());
        assert_eq!(half.engager_by_way(&o, ball), Some(2));
        // Player 1 lined up behind the ball at 0.5 m: it is nearer and
        // has no detour, so it goes.
        o.own[1] = robot(-0.5, 0.1, 0.0);
        assert_eq!(by_way.engager_by_way(&o, ball), Some(1));
        // ...unless it must turn round (engage_turn, per radian).
        o.own[1].heading = std::f32::consts::PI;
        let turning =
            Scripted::new(ScriptedParams::parse_spec("engage_path=1,engage_turn=0.2").unwrap());
        assert_eq!(turning.engager_by_way(&o, ball), Some(2));
        // The player in control keeps the ball either way.
        o.control[1] = true;
        assert_eq!(turning.engager_by_way(&o, ball), Some(1));
    }

    #[test]
    fn off_values_are_the_defaults_and_bad_values_are_refused() {
        let d = ScriptedParams::default();
        assert_eq!(
            (d.react_ticks, d.aim_offset, d.keeper_guard, d.markers),
            (1.0, 0.0, 0.0, 0.0)
        );
        assert_eq!((d.set_play_guard, d.set_play_pass), (0.0, 0.0));
        assert_eq!((d.hold_turns, d.aimed_pass), (1.0, 0.0));
        let err = |s: &str| ScriptedParams::parse_spec(s).unwrap_err();
        assert!(err("react_ticks=0").contains("react_ticks"));
        assert!(err("react_ticks=1.5").contains("whole number"));
        assert!(err("markers=3").contains("markers"));
        assert!(err("hold_turns=2").contains("hold_turns"));
        assert!(err("aimed_pass=-1").contains("aimed_pass"));
        assert!(err("set_play_guard=0.5").contains("set_play_guard"));
        assert!(err("aim_offset=1.3").contains("inside the goal"));
        assert!(err("keep_out=-1").contains("keep_out"));
    }

    #[test]
    fn a_slow_player_holds_its_action_between_decisions() {
        let p = ScriptedParams::parse_spec("react_ticks=3").unwrap();
        let mut s = Scripted::new(p);
        // Player 1 decides when (tick + 1) % 3 == 0: at tick 2, then 5.
        let mut o = obs(1, robot(0.0, 0.0, 1.2), [1.0, 0.0]);
        o.tick = Tick::new(2);
        assert_eq!(s.act(&o), Action::TurnRight);
        // Facing the ball now, but it keeps turning until it decides again.
        let mut o = obs(1, robot(0.0, 0.0, 0.0), [1.0, 0.0]);
        for t in [3, 4] {
            o.tick = Tick::new(t);
            assert_eq!(s.act(&o), Action::TurnRight, "tick {t}");
        }
        o.tick = Tick::new(5);
        assert_eq!(s.act(&o), Action::Forward);
        // With hold_turns=0 a turning player decides again every tick.
        let p = ScriptedParams::parse_spec("react_ticks=3,hold_turns=0").unwrap();
        let mut s = Scripted::new(p);
        let mut o = obs(1, robot(0.0, 0.0, 1.2), [1.0, 0.0]);
        o.tick = Tick::new(2);
        assert_eq!(s.act(&o), Action::TurnRight);
        let mut o = obs(1, robot(0.0, 0.0, 0.0), [1.0, 0.0]);
        o.tick = Tick::new(3);
        assert_eq!(s.act(&o), Action::Forward);
        // ...but holds its walk until the next decision.
        let mut o = obs(1, robot(0.0, 0.0, 1.2), [1.0, 0.0]);
        o.tick = Tick::new(4);
        assert_eq!(s.act(&o), Action::Forward);
    }

    #[test]
    fn an_aimed_pass_goes_to_a_teammate_ahead() {
        // Player 1 at the ball facing +x; player 2 ahead in the cone, 1.5 m.
        let mut o = obs(1, robot(-1.0, 0.0, 0.0), [-0.82, 0.0]);
        o.own[2] = robot(0.7, 0.3, 0.0);
        assert_eq!(pass_receiver(&o), Some(2));
        let p = ScriptedParams::parse_spec("aimed_pass=1").unwrap();
        assert_eq!(Scripted::new(p).act(&o), Action::Pass);
        // Today's team kicks straight ahead when a teammate is in its line of
        // fire, and dribbles otherwise.
        let today = Scripted::new(ScriptedParams::default()).act(&o);
        assert!(
            matches!(today, Action::Shoot | Action::Forward),
            "{today:?}"
        );
    }

    #[test]
    fn a_guarding_keeper_stands_between_ball_and_goal() {
        let p = ScriptedParams::parse_spec("keeper_guard=1").unwrap();
        let ball = [0.0f32, 1.5];
        // Its place: 1 m from the goal centre (-3, 0) toward the ball.
        let u = [3.0 / 45f32.sqrt() * 2.0, 1.5 / 45f32.sqrt() * 2.0];
        let place = [-3.0 + u[0], u[1]];
        let facing = robot(
            place[0],
            place[1],
            (ball[1] - place[1]).atan2(ball[0] - place[0]),
        );
        assert_eq!(Scripted::new(p).act(&obs(0, facing, ball)), Action::Stay);
        // Today's keeper stands on its line (y follows the ball), so it
        // walks back from there.
        let today = Scripted::new(ScriptedParams::default()).act(&obs(0, facing, ball));
        assert_ne!(today, Action::Stay);
    }

    #[test]
    fn at_the_other_teams_set_play_a_guard_blocks_the_way_to_goal() {
        use naosoccer_proto::{SetPlayKind, SetPlayObs};
        let p = ScriptedParams::parse_spec("set_play_guard=1").unwrap();
        // A kick-in at (1, 2.2) for the other team; player 1, the nearest
        // to the ball, stands 1.6 m below it, facing it.
        let ball = [1.0f32, 2.2];
        let heading = std::f32::consts::FRAC_PI_2;
        let mut o = obs(1, robot(1.0, 0.6, heading), ball);
        o.set_play = Some(SetPlayObs {
            kind: SetPlayKind::KickIn,
            own: false,
            ticks_left: 100,
        });
        // It turns toward the spot on the line from the ball to its goal,
        // 0.7 m from the ball...
        let to = [-3.0 - ball[0], -ball[1]];
        let n = norm(to);
        let spot = [ball[0] + 0.7 * to[0] / n, ball[1] + 0.7 * to[1] / n];
        let err = wrap((spot[1] - 0.6).atan2(spot[0] - 1.0) - heading);
        assert!(err > p.turn_start, "{err}");
        assert_eq!(Scripted::new(p).act(&o), Action::TurnLeft);
        // ...where today's player walks on toward the ball.
        let today = Scripted::new(ScriptedParams::default()).act(&o);
        assert_eq!(today, Action::Forward);
        // At its own set play it plays as today's team does.
        o.set_play = Some(SetPlayObs {
            kind: SetPlayKind::KickIn,
            own: true,
            ticks_left: 100,
        });
        assert_eq!(
            Scripted::new(p).act(&o),
            Scripted::new(ScriptedParams::default()).act(&o)
        );
    }

    /// `set_play_guard` counts the guards, nearest the ball first: with 1
    /// only the nearest field player leaves the ball alone; with 3 the
    /// others guard the lanes too.
    #[test]
    fn the_set_play_guard_counts_its_guards() {
        use naosoccer_proto::{SetPlayKind, SetPlayObs};
        // A kick-in at (1, 2.2) for the other team; player 2 is the
        // second-nearest field player, 1.2 m from the ball, facing it.
        let ball = [1.0f32, 2.2];
        let mut o = obs(2, robot(0.0, 1.5, 0.6), ball);
        o.own[1] = robot(1.0, 1.4, std::f32::consts::FRAC_PI_2);
        o.own[3] = robot(-1.5, -1.0, 0.0);
        o.opponents[1] = robot(1.0, 2.4, 0.0);
        o.opponents[2] = robot(0.2, 2.0, 0.0);
        o.set_play = Some(SetPlayKind::KickIn).map(|kind| SetPlayObs {
            kind,
            own: false,
            ticks_left: 100,
        });
        assert_eq!(guard_rank(&o), 1);
        let guard = |n: &str| ScriptedParams::parse_spec(&format!("set_play_guard={n}")).unwrap();
        let plain = Scripted::new(ScriptedParams::default()).act(&o);
        // One guard: the second-nearest plays as the plain team.
        assert_eq!(Scripted::new(guard("1")).act(&o), plain);
        // Three: it goes to the lane toward the likeliest receiver instead.
        let mut three = Scripted::new(guard("3"));
        let want = three.guard_set_play(&o);
        assert_eq!(Scripted::new(guard("3")).act(&o), want);
        assert_ne!(want, plain, "the guard and the plain team must differ here");
        assert!(ScriptedParams::parse_spec("set_play_guard=4").is_err());
    }

    #[test]
    fn around_a_circle_the_path_bends() {
        // Straight through the ball: a waypoint on the circle instead.
        let w = around([0.0, 0.0], [-2.0, 0.0], [2.0, 0.0], 0.7);
        assert!((norm(w) - 2.0).abs() < 1e-5, "{w:?}");
        // A clear path: the target itself.
        assert_eq!(around([0.0, 0.0], [-2.0, 1.0], [2.0, 1.0], 0.7), [2.0, 1.0]);
    }

    #[test]
    fn keeper_stays_home_until_the_ball_comes_near() {
        let mut s = Scripted::new(ScriptedParams::default());
        // At home, ball far away in front: just faces it.
        let o = obs(0, robot(-2.65, 0.0, 0.0), [1.0, 0.0]);
        assert_eq!(s.act(&o), Action::Stay);
        // Ball in its zone, straight ahead: goes for it.
        let o = obs(0, robot(-2.65, 0.0, 0.0), [-2.0, 0.0]);
        assert_eq!(s.act(&o), Action::Forward);
    }

    #[test]
    fn fallen_robot_stays() {
        let mut s = Scripted::new(ScriptedParams::default());
        let mut me = robot(0.0, 0.0, 0.0);
        me.fallen = true;
        assert_eq!(s.act(&obs(2, me, [0.5, 0.0])), Action::Stay);
    }
}
