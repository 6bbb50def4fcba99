//! What the actions that are not protocol actions turn into: the
//! `support`, `approach`, `defend` and `give` steps, their spots, and their
//! tuning.

use naosoccer_proto::{lane_blocked, pass_receiver, Action, Observation, PASS_CONE, PASS_LANE};
use naosoccer_referee::rules::wrap_angle;

use super::masks::nearest_standing_teammate;
use super::{NetAction, SupportSpot};
use crate::obs::KickReach;

/// A support spot lies this far ahead of the ball, toward the opponent
/// goal (m): the default of the reward's `support_ahead`.
pub const SUPPORT_AHEAD: f32 = 1.5;
/// ...and this far to the side of the ball the robot is on (m): the
/// default of the reward's `support_side`. The spot is 1.8 m from the ball
/// and 0.59 rad off the line toward the goal, inside the pass rule's
/// 0.8-4 m and 0.8 rad for a kicker facing the goal.
pub const SUPPORT_SIDE: f32 = 1.0;
/// Within this distance of its spot (m) a supporting robot turns to face
/// the ball instead of walking.
pub const SUPPORT_ARRIVE: f32 = 0.3;
/// A supporting robot walks when its spot is within this angle of its
/// heading (rad) and turns toward it otherwise.
pub const SUPPORT_WALK_CONE: f32 = 0.35;
/// Arrived, it turns until the ball is within this angle of its heading (rad).
pub const SUPPORT_FACE_CONE: f32 = 0.5;
/// With [`DecisionConfig::support_hold`](super::DecisionConfig::support_hold),
/// a held `support` also ends once the ball is this close to the robot (m),
/// so a robot that a pass reaches decides at once.
pub const SUPPORT_RELEASE_BALL: f32 = 0.6;

/// `approach` walks straight into the ball once the robot stands within
/// this angle (rad) of the line from the ball to the opponent goal, seen
/// from the ball (within twice it when closer than [`APPROACH_NEAR`]); the
/// scripted team's `align_tolerance`.
pub const APPROACH_ALIGN: f32 = 0.5;
/// See [`APPROACH_ALIGN`] (m).
pub const APPROACH_NEAR: f32 = 0.25;
/// Out of line, `approach` first walks to this far behind the ball on that
/// line (m): the scripted team's `behind`.
pub const APPROACH_BEHIND: f32 = 0.3;
/// Walking into the ball, `approach` turns while the ball would pass more
/// than this far (m) to the side of the robot's heading line...
pub const APPROACH_LATERAL: f32 = 0.06;
/// ...but never for an angle error below this (rad).
pub const APPROACH_MIN_CONE: f32 = 0.12;

/// `defend` walks to this far from the ball (m) on the line from the ball
/// to the centre of the own goal: between the ball and the goal, near
/// enough to meet a dribble, as the scripted team's covering player stays
/// 1.2 m behind the ball.
pub const DEFEND_BEHIND: f32 = 1.0;
/// ...but never nearer the own goal's centre than this (m), so that a
/// defender stands in front of its goal, not in it.
pub const DEFEND_GOAL_MIN: f32 = 0.3;
/// A `defend` whose straight walk would pass the ball nearer than this
/// (m, centre to centre) goes round the ball instead...
pub const DEFEND_CLEARANCE: f32 = 0.35;
/// ...by a point this far (m) beside the ball.
pub const DEFEND_WIDE: f32 = 0.55;

/// `give` lines up on a teammate at least this far from the ball (m):
/// the pass rule's 0.8 m with room for the teammate to move while the
/// kicker lines up, and over the reward's 1 m `pass_min_distance`.
pub const GIVE_MIN: f32 = 1.2;
/// ...and at most this far (m), inside the pass rule's 4 m.
pub const GIVE_MAX: f32 = 3.5;
/// A `give` held under [`DecisionConfig::support_hold`](super::DecisionConfig::support_hold)
/// ends once the ball is farther than this from the robot (m): its pass
/// was made, or the ball was lost.
pub const GIVE_RELEASE_BALL: f32 = 1.0;

/// The protocol action the network action `a` stands for in the state
/// `obs`, on a pitch of half length and half width `half`: itself for the
/// protocol's actions, the step toward the support spot (placed as `spot`
/// says) for `support`, the step of [`approach_action`] for `approach`,
/// the step of [`defend_action`] for `defend`, the step or kick of
/// [`give_action`] (with the kick reach `reach`) for `give`.
pub fn to_action(
    a: NetAction,
    obs: &Observation,
    half: [f32; 2],
    spot: SupportSpot,
    reach: &KickReach,
) -> Action {
    match a {
        NetAction::Forward => Action::Forward,
        NetAction::TurnLeft => Action::TurnLeft,
        NetAction::TurnRight => Action::TurnRight,
        NetAction::Shoot => Action::Shoot,
        NetAction::Stay => Action::Stay,
        NetAction::Pass => Action::Pass,
        NetAction::Support => support_action(obs, half, spot),
        NetAction::Approach => approach_action(obs, half),
        NetAction::Defend => defend_action(obs, half),
        NetAction::Give => give_action(obs, half, reach),
    }
}

/// The teammate (player number) a `give` by the robot that received `obs`
/// lines up on, if any: a standing teammate other than the robot,
/// [`GIVE_MIN`] to [`GIVE_MAX`] from the ball, with no opponent (standing or
/// lying) within the pass rule's lane ([`PASS_LANE`]) of the line from the
/// ball to it, whatever the robot's heading. Teammates level with the ball
/// or ahead of it (toward the opponent goal) come first; of those, the one
/// the robot needs to walk least round the ball for: the smallest angle
/// between the robot's way to the ball (its heading, within 5 cm of the
/// ball) and the ball's way to the teammate; on a tie the lower player
/// number. Computed from the observation alone, so it is the same in
/// training, in process and over the socket.
pub fn give_target(obs: &Observation) -> Option<usize> {
    let me = obs.player.index();
    let r = obs.me();
    let (bx, by) = (obs.ball.x, obs.ball.y);
    let (mx, my) = (bx - r.x, by - r.y);
    let approach = if mx.hypot(my) > 0.05 {
        my.atan2(mx)
    } else {
        r.heading
    };
    let mut best: Option<(bool, f32, usize)> = None;
    for (j, t) in obs.own.iter().enumerate() {
        if j == me || t.fallen {
            continue;
        }
        let (dx, dy) = (t.x - bx, t.y - by);
        let d = dx.hypot(dy);
        if !(GIVE_MIN..=GIVE_MAX).contains(&d) {
            continue;
        }
        if lane_blocked(obs, [bx, by], [dx, dy], PASS_LANE) {
            continue;
        }
        let behind = dx < 0.0;
        let off = wrap_angle(dy.atan2(dx) - approach).abs();
        let better = match best {
            None => true,
            Some((b, o, _)) => (behind, off) < (b, o),
        };
        if better {
            best = Some((behind, off, j));
        }
    }
    best.map(|(_, _, j)| j)
}

/// The `give` action's step for the robot that received `obs`, on a pitch
/// of half length and half width `half` (m), with the kick reach `reach`:
/// facing the teammate of [`give_target`] (within the pass rule's cone,
/// [`PASS_CONE`]) with the ball in reach and a receiver named by the pass
/// rule (`proto::pass_receiver`: that teammate or another in the cone), the
/// protocol's `pass`; otherwise it lines up on that teammate as
/// [`approach_action`] lines up on the opponent goal (round behind the ball
/// onto the line from the teammate through the ball, then into the ball),
/// so that it reaches the ball facing the teammate, where the pass rule
/// names a receiver. With no such teammate, `approach`'s step. A lying
/// robot stays. Stateless, so it is the same step in training, in process
/// and over the socket.
pub fn give_action(obs: &Observation, half: [f32; 2], reach: &KickReach) -> Action {
    if obs.me().fallen {
        return Action::Stay;
    }
    let Some(j) = give_target(obs) else {
        return approach_action(obs, half);
    };
    let t = &obs.own[j];
    let to = [t.x - obs.ball.x, t.y - obs.ball.y];
    let facing = wrap_angle(to[1].atan2(to[0]) - obs.me().heading).abs() <= PASS_CONE;
    if facing && reach.in_reach(obs) && pass_receiver(obs).is_some() {
        return Action::Pass;
    }
    line_up(obs, to)
}

/// The `approach` action's step for the robot that received `obs`, on a
/// pitch of half length and half width `half` (m), as the scripted team
/// lines up: seen from the ball, when the robot stands within
/// [`APPROACH_ALIGN`] of the line from the ball to the opponent goal's
/// centre, it turns to the ball (while the ball would pass more than
/// [`APPROACH_LATERAL`] to the side, or [`APPROACH_MIN_CONE`]) and walks
/// into it, so it reaches the ball facing the goal and walks on with it.
/// Otherwise it walks round to [`APPROACH_BEHIND`] behind the ball on that
/// line, going wide of the ball when the ball is in the way. Stateless, so
/// it is the same step in training, in process and over the socket.
pub fn approach_action(obs: &Observation, half: [f32; 2]) -> Action {
    line_up(obs, [half[0] - obs.ball.x, -obs.ball.y])
}

/// The step of the robot that received `obs` lining up to play the ball
/// along `to` (from the ball, any length): [`approach_action`] with `to`
/// in place of the way to the opponent goal's centre.
fn line_up(obs: &Observation, to: [f32; 2]) -> Action {
    let me = obs.me();
    if me.fallen {
        return Action::Stay;
    }
    let ball = [obs.ball.x, obs.ball.y];
    let len = to[0].hypot(to[1]);
    let u = if len > 1e-6 {
        [to[0] / len, to[1] / len]
    } else {
        [1.0, 0.0]
    };
    let to_ball = [ball[0] - me.x, ball[1] - me.y];
    let d = to_ball[0].hypot(to_ball[1]);
    let ball_dir = to_ball[1].atan2(to_ball[0]);
    let off = wrap_angle(ball_dir - u[1].atan2(u[0])).abs();
    let (target, cone) =
        if off < APPROACH_ALIGN || (d < APPROACH_NEAR && off < 2.0 * APPROACH_ALIGN) {
            let cone = (APPROACH_LATERAL / d.max(1e-3))
                .atan()
                .clamp(APPROACH_MIN_CONE, SUPPORT_WALK_CONE);
            (ball, cone)
        } else {
            let rel = [me.x - ball[0], me.y - ball[1]];
            let along = rel[0] * u[0] + rel[1] * u[1];
            let across = u[0] * rel[1] - u[1] * rel[0];
            let target = if along > -0.15 && across.abs() < 0.45 {
                // The ball is in the way: go wide of it first, to a point
                // as far behind the ball as the line-up point. Walking there
                // always leaves this region; a point on its edge (0.15 m
                // behind, as the scripted team goes wide) could leave the
                // robot there, turning left and right for ever as it
                // swayed across the edge.
                let side = if across >= 0.0 { 1.0 } else { -1.0 };
                [
                    ball[0] - u[1] * side * 0.5 - u[0] * APPROACH_BEHIND,
                    ball[1] + u[0] * side * 0.5 - u[1] * APPROACH_BEHIND,
                ]
            } else {
                [
                    ball[0] - u[0] * APPROACH_BEHIND,
                    ball[1] - u[1] * APPROACH_BEHIND,
                ]
            };
            (target, SUPPORT_WALK_CONE)
        };
    steer(me, target, cone)
}

/// The step of robot `me` heading for `target` (m): a turn toward it while
/// it lies more than `cone` (rad) off the heading, `forward` otherwise.
fn steer(me: &naosoccer_proto::RobotObs, target: [f32; 2], cone: f32) -> Action {
    let err = wrap_angle((target[1] - me.y).atan2(target[0] - me.x) - me.heading);
    if err.abs() > cone {
        if err > 0.0 {
            Action::TurnLeft
        } else {
            Action::TurnRight
        }
    } else {
        Action::Forward
    }
}

/// The `support` action's step for the robot that received `obs`, on a
/// pitch of half length and half width `half` (m): its support spot
/// ([`support_spot`], placed as `spot` says) is by default
/// [`SUPPORT_AHEAD`] ahead of the ball (toward the opponent goal, +x in the
/// observation's frame) and [`SUPPORT_SIDE`] to the side of the ball the
/// robot stands on, kept 0.3 m inside the lines (the reward's `support`
/// spot). Away from the spot it turns toward it until the spot is within
/// [`SUPPORT_WALK_CONE`] and walks; arrived, it turns to face the ball.
/// Stateless, so it is the same step in training, in process and over the
/// socket.
pub fn support_action(obs: &Observation, half: [f32; 2], spot: SupportSpot) -> Action {
    walk_spot(obs, support_spot(obs, half, spot))
}

/// The `defend` action's step for the robot that received `obs`, on a
/// pitch of half length and half width `half` (m): a walk to its defending
/// spot ([`defend_spot`]), turning toward it until it is within
/// [`SUPPORT_WALK_CONE`]; arrived (within [`SUPPORT_ARRIVE`]), it turns to
/// face the ball. A robot whose straight walk to the spot would pass
/// within [`DEFEND_CLEARANCE`] of the ball (it stands upfield of the ball)
/// goes round it first, to [`DEFEND_WIDE`] beside the ball on the side it
/// stands, so that it does not push the ball toward its own goal on the
/// way back. Stateless, so it is the same step in training, in process and
/// over the socket.
pub fn defend_action(obs: &Observation, half: [f32; 2]) -> Action {
    let spot = defend_spot(obs, half);
    let me = obs.me();
    let ball = [obs.ball.x, obs.ball.y];
    let path = [spot[0] - me.x, spot[1] - me.y];
    let len2 = path[0] * path[0] + path[1] * path[1];
    let t = if len2 > 1e-9 {
        ((ball[0] - me.x) * path[0] + (ball[1] - me.y) * path[1]) / len2
    } else {
        -1.0
    };
    let target = if (0.0..1.0).contains(&t) {
        let near = [me.x + t * path[0], me.y + t * path[1]];
        if (ball[0] - near[0]).hypot(ball[1] - near[1]) < DEFEND_CLEARANCE {
            // Beside the ball, across the line from the ball to the spot,
            // on the side the robot stands.
            let (ux, uy) = {
                let d = [spot[0] - ball[0], spot[1] - ball[1]];
                let l = d[0].hypot(d[1]).max(1e-6);
                (d[0] / l, d[1] / l)
            };
            let across = ux * (me.y - ball[1]) - uy * (me.x - ball[0]);
            let side = if across >= 0.0 { 1.0 } else { -1.0 };
            [
                ball[0] - uy * side * DEFEND_WIDE,
                ball[1] + ux * side * DEFEND_WIDE,
            ]
        } else {
            spot
        }
    } else {
        spot
    };
    if target == spot {
        walk_spot(obs, spot)
    } else if me.fallen {
        Action::Stay
    } else {
        steer(me, target, SUPPORT_WALK_CONE)
    }
}

/// The defending spot of the robot that received `obs` (observation frame,
/// the own goal's centre at (-half length, 0), m): on the line from the
/// ball to that centre, [`DEFEND_BEHIND`] from the ball, but at least
/// [`DEFEND_GOAL_MIN`] from the goal's centre (the ball nearer its goal
/// than that: the point that far out toward the ball), and at least 0.1 m
/// in front of the goal line.
pub fn defend_spot(obs: &Observation, half: [f32; 2]) -> [f32; 2] {
    let goal = [-half[0], 0.0];
    let (dx, dy) = (obs.ball.x - goal[0], obs.ball.y - goal[1]);
    let len = dx.hypot(dy);
    let (ux, uy) = if len > 1e-6 {
        (dx / len, dy / len)
    } else {
        (1.0, 0.0)
    };
    let from_goal = (len - DEFEND_BEHIND).max(DEFEND_GOAL_MIN);
    [
        (goal[0] + ux * from_goal).max(goal[0] + 0.1),
        (goal[1] + uy * from_goal).clamp(-half[1], half[1]),
    ]
}

/// The step of a robot that received `obs` walking to `spot` (observation
/// frame, m) and facing the ball there: away from the spot it turns
/// toward it until the spot is within [`SUPPORT_WALK_CONE`] and walks;
/// within [`SUPPORT_ARRIVE`] of it, it turns until the ball is within
/// [`SUPPORT_FACE_CONE`] and stays. A lying robot stays.
pub fn walk_spot(obs: &Observation, spot: [f32; 2]) -> Action {
    let me = obs.me();
    if me.fallen {
        return Action::Stay;
    }
    let (bx, by) = (obs.ball.x, obs.ball.y);
    let (dx, dy) = (spot[0] - me.x, spot[1] - me.y);
    let (target, cone, arrived) = if dx.hypot(dy) > SUPPORT_ARRIVE {
        ([dx, dy], SUPPORT_WALK_CONE, false)
    } else {
        ([bx - me.x, by - me.y], SUPPORT_FACE_CONE, true)
    };
    let err = wrap_angle(target[1].atan2(target[0]) - me.heading);
    if err.abs() > cone {
        if err > 0.0 {
            Action::TurnLeft
        } else {
            Action::TurnRight
        }
    } else if arrived {
        Action::Stay
    } else {
        Action::Forward
    }
}

/// The support spot of the robot that received `obs` (observation frame,
/// m), kept 0.3 m inside the lines of a pitch of half length and half
/// width `half`. [`SupportSpot::Ahead`]: [`SUPPORT_AHEAD`] ahead of the
/// ball (+x) and [`SUPPORT_SIDE`] to the side of it the robot stands on.
/// [`SupportSpot::Facing`]: [`SUPPORT_AHEAD`] beyond the ball on the line
/// from the standing teammate nearest the ball (on a tie the lower player
/// number; not the robot itself) through the ball, and [`SUPPORT_SIDE`] to
/// the side of that line the robot stands on; with no such teammate, or
/// one on the ball's centre, as `Ahead`.
pub fn support_spot(obs: &Observation, half: [f32; 2], spot: SupportSpot) -> [f32; 2] {
    let me = obs.me();
    let (bx, by) = (obs.ball.x, obs.ball.y);
    let (lx, ly) = ((half[0] - 0.3).max(0.0), (half[1] - 0.3).max(0.0));
    let mut dir = [1.0, 0.0];
    if spot == SupportSpot::Facing {
        if let Some((len, j)) = nearest_standing_teammate(obs) {
            if len > 1e-3 {
                let k = &obs.own[j];
                dir = [(bx - k.x) / len, (by - k.y) / len];
            }
        }
    }
    // Left of the line (looking along `dir`) is +1.
    let side = if dir[0] * (me.y - by) - dir[1] * (me.x - bx) >= 0.0 {
        1.0
    } else {
        -1.0
    };
    [
        (bx + dir[0] * SUPPORT_AHEAD - dir[1] * side * SUPPORT_SIDE).clamp(-lx, lx),
        (by + dir[1] * SUPPORT_AHEAD + dir[0] * side * SUPPORT_SIDE).clamp(-ly, ly),
    ]
}
