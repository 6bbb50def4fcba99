//! The action table and how a network's outputs become actions: the five
//! discrete actions, the decision-level MDP's holds, the sampling draws and
//! the inverse-CDF sampler. Training (crates/learn) and play share them, so
//! a team decides in play exactly as it did in training.

use naosoccer_proto::{Action, Observation, Tick};
use naosoccer_referee::rules::wrap_angle;
use serde::{Deserialize, Serialize};

use crate::guard::OwnGoalGuard;

/// The paper's discrete actions, in `proto::Action::from_index` order:
/// forward, turn left, turn right, shoot, stay. A team trained with
/// [`DecisionConfig::pass`] has a sixth, `pass` ([`PASS`]), one trained
/// with [`DecisionConfig::support`] a seventh, `support` ([`SUPPORT`]), and
/// one trained with [`DecisionConfig::approach`] an eighth, `approach`
/// ([`APPROACH`]).
pub const ACTIONS: usize = 5;

/// The most actions a network has (the paper's five, `pass`, `support`
/// and `approach`).
pub const MAX_ACTIONS: usize = 8;

/// Index of `pass`, the sixth action of teams trained with it.
pub const PASS: usize = 5;

/// Index of `support`, the seventh action of teams trained with it. It is
/// not a protocol action: the team's policy turns it, every tick, into the
/// `forward`, turn or `stay` that walks the robot to its support spot
/// ([`support_action`]).
pub const SUPPORT: usize = 6;

/// Index of `approach`, the eighth action of teams trained with it. Like
/// `support` it is not a protocol action: the team's policy turns it, every
/// tick, into the `forward` or turn that walks the robot round behind the
/// ball, onto the line from the ball to the opponent goal, and then into
/// the ball facing that way ([`approach_action`]).
pub const APPROACH: usize = 7;

/// The actions' names, by index: the protocol's five, then `pass`,
/// `support` and `approach`.
pub const ACTION_NAMES: [&str; MAX_ACTIONS] = [
    "forward",
    "turn_left",
    "turn_right",
    "shoot",
    "stay",
    "pass",
    "support",
    "approach",
];

/// Index of `forward`.
pub const FORWARD: usize = 0;

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
/// With [`DecisionConfig::support_hold`], a held `support` also ends once
/// the ball is this close to the robot (m), so a robot that a pass reaches
/// decides at once.
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

/// Index of `turn_left`.
pub const TURN_LEFT: usize = 1;
/// Index of `turn_right`.
pub const TURN_RIGHT: usize = 2;
/// Index of `shoot` among the actions.
pub const SHOOT: usize = 3;
/// Index of `stay`.
pub const STAY: usize = 4;

/// A logit this low makes an action impossible (its probability underflows to 0).
pub const MASKED_LOGIT: f32 = -1e9;

/// The decision-level MDP (`team` presets). A setting this build does not
/// know is refused rather than ignored: a team trained with it would
/// otherwise play here without it, silently differently.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DecisionConfig {
    /// Ticks a movement decision (`forward`, turns, `stay`) lasts before the
    /// robot decides again (a `shoot` lasts as long as the kick keeps it busy).
    pub persist: u32,
    /// `shoot` is impossible while the ball is out of kick reach.
    pub mask_shoot: bool,
    /// The robots have a sixth action, `pass` (protocol 1.3), possible only
    /// while the ball is in kick reach and `proto::pass_receiver` names a
    /// teammate. Absent from older runs' configurations: `false`.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub pass: bool,
    /// The robots have a seventh action, `support` (needs `pass`): walk to
    /// the support spot ahead of the ball ([`support_action`]), where a
    /// teammate with the ball can pass to them. Always possible. Absent
    /// from older runs' configurations: `false`.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub support: bool,
    /// With `support`: the most ticks one `support` decision holds. The
    /// robot then walks on to its spot without deciding again until it
    /// arrives (within [`SUPPORT_ARRIVE`]), the ball comes within
    /// [`SUPPORT_RELEASE_BALL`] of it, or this many ticks pass, and holds
    /// at least `persist` ticks as any movement does. One choice of
    /// `support` then puts a robot ahead of the ball, where a one-tick
    /// choice moved it a few centimetres. 0 (and absent from older runs'
    /// configurations): `support` holds `persist` ticks like any movement.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub support_hold: u32,
    /// With `support`: roles. Only the team's `chasers` standing robots
    /// nearest the ball ([`is_chaser`]) may `forward` or turn; the others
    /// choose among `support`, `stay` and, with the ball in reach, `shoot`
    /// and `pass`, so that the robots away from the ball stand where a pass
    /// can reach them instead of crowding it. 0 (and absent from older
    /// runs' configurations): no roles.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub chasers: u32,
    /// With `chasers`: the robots that do not chase may not `stay` either
    /// ([`SUPPORT_ONLY_BANNED`]), so they always walk to or hold their
    /// support spot unless the ball is in reach. Absent from older runs'
    /// configurations: `false`.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub support_only: bool,
    /// With `support`: where the support spot is ([`SupportSpot`]). Absent
    /// from older runs' configurations: [`SupportSpot::Ahead`].
    #[serde(default, skip_serializing_if = "SupportSpot::is_ahead")]
    pub support_spot: SupportSpot,
    /// The robots have an eighth action, `approach` (needs `support`): walk
    /// round behind the ball onto its line to the opponent goal, then into
    /// it ([`approach_action`]). Under `chasers`, the robots that do not
    /// chase may not `approach` either. Absent from older runs'
    /// configurations: `false`.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub approach: bool,
    /// With `approach`: no robot may `forward` or turn; the robots move by
    /// `approach` and `support` only ([`APPROACH_ONLY_BANNED`]). Absent
    /// from older runs' configurations: `false`.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub approach_only: bool,
    /// The own-goal guard ([`OwnGoalGuard`]): near its own goal a robot
    /// facing that goal may not walk into the ball or kick it. Absent from
    /// older runs' configurations: off.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub own_goal_guard: Option<OwnGoalGuard>,
}

fn is_zero(v: &u32) -> bool {
    *v == 0
}

/// Where a `support` walks to ([`support_spot`]).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SupportSpot {
    /// [`SUPPORT_AHEAD`] ahead of the ball toward the opponent goal and
    /// [`SUPPORT_SIDE`] to the side the robot is on.
    #[default]
    Ahead,
    /// [`SUPPORT_AHEAD`] beyond the ball on the line from the teammate
    /// nearest the ball (the one about to kick it) through the ball, and
    /// [`SUPPORT_SIDE`] to the side of that line the robot is on: where the
    /// kicker faces when it reaches the ball, whichever way that is.
    Facing,
}

impl SupportSpot {
    fn is_ahead(&self) -> bool {
        *self == SupportSpot::Ahead
    }
}

impl DecisionConfig {
    /// The `team` presets' decisions: a movement holds 3 ticks, `shoot` is
    /// masked while the ball is out of reach, the five protocol actions of
    /// the paper and nothing more (each extra is switched on by a `train`
    /// flag).
    pub fn team() -> DecisionConfig {
        DecisionConfig {
            persist: 3,
            mask_shoot: true,
            pass: false,
            support: false,
            support_hold: 0,
            chasers: 0,
            support_only: false,
            support_spot: SupportSpot::Ahead,
            approach: false,
            approach_only: false,
            own_goal_guard: None,
        }
    }

    /// How many actions the networks choose among: 5, 6 with `pass`, 7
    /// with `pass` and `support`, 8 with `approach` too.
    pub fn actions(&self) -> usize {
        match (self.pass, self.support, self.approach) {
            (_, true, true) => APPROACH + 1,
            (_, true, false) => SUPPORT + 1,
            (true, false, _) => PASS + 1,
            (false, false, _) => ACTIONS,
        }
    }
}

/// The protocol action a team's action index `index` stands for in the
/// state `obs`, on a pitch of half length and half width `half`: the index
/// itself for the protocol's actions, the step toward the support spot
/// (placed as `spot` says) for [`SUPPORT`], the step of [`approach_action`]
/// for [`APPROACH`], `stay` for anything else.
pub fn to_action(index: usize, obs: &Observation, half: [f32; 2], spot: SupportSpot) -> Action {
    match index {
        SUPPORT => support_action(obs, half, spot),
        APPROACH => approach_action(obs, half),
        _ => Action::from_index(index).unwrap_or(Action::Stay),
    }
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
    let me = obs.me();
    if me.fallen {
        return Action::Stay;
    }
    let ball = [obs.ball.x, obs.ball.y];
    let to_goal = [half[0] - ball[0], -ball[1]];
    let len = to_goal[0].hypot(to_goal[1]);
    let u = if len > 1e-6 {
        [to_goal[0] / len, to_goal[1] / len]
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
    let me = obs.me();
    if me.fallen {
        return Action::Stay;
    }
    let (bx, by) = (obs.ball.x, obs.ball.y);
    let spot = support_spot(obs, half, spot);
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

/// The number of actions of a team in `decision` (`None`: the paper's five).
pub fn action_count(decision: Option<DecisionConfig>) -> usize {
    decision.map_or(ACTIONS, |d| d.actions())
}

/// Whether the robot that received `obs` may `pass` now: the ball is in
/// kick reach (`in_reach`, from the encoder) and there is a receiver.
pub fn pass_possible(obs: &Observation, in_reach: bool) -> bool {
    in_reach && naosoccer_proto::pass_receiver(obs).is_some()
}

/// Whether the robot that received `obs` is one of its team's `chasers`
/// under [`DecisionConfig::chasers`]: it stands, and fewer than `chasers`
/// standing teammates are nearer the ball (on a tie, the lower player
/// number is nearer). Read from the observation alone, so in-process and
/// socket play agree.
pub fn is_chaser(obs: &Observation, chasers: u32) -> bool {
    let me = obs.player.index();
    if obs.own[me].fallen {
        return false;
    }
    let mine = ball_distance(obs, &obs.own[me]);
    let nearer = standing_teammates(obs)
        .filter(|&(j, d)| d < mine || (d == mine && j < me))
        .count();
    nearer < chasers as usize
}

/// How far `r` stands from the ball in `obs`, metres.
fn ball_distance(obs: &Observation, r: &naosoccer_proto::RobotObs) -> f32 {
    (r.x - obs.ball.x).hypot(r.y - obs.ball.y)
}

/// The standing teammates of the robot that received `obs` (not the robot
/// itself), as (player number, distance to the ball), by player number.
fn standing_teammates(obs: &Observation) -> impl Iterator<Item = (usize, f32)> + '_ {
    let me = obs.player.index();
    obs.own
        .iter()
        .enumerate()
        .filter(move |&(j, r)| j != me && !r.fallen)
        .map(|(j, r)| (j, ball_distance(obs, r)))
}

/// The standing teammate nearest the ball (on a tie the lower player
/// number; not the robot itself), as (distance to the ball, player
/// number), or `None` with every teammate down.
fn nearest_standing_teammate(obs: &Observation) -> Option<(f32, usize)> {
    standing_teammates(obs).fold(None, |best, (j, d)| match best {
        Some((b, _)) if b <= d => best,
        _ => Some((d, j)),
    })
}

/// The actions a robot that is not one of its team's chasers may not choose
/// under [`DecisionConfig::chasers`], as bits (`1 << index`): `forward` and
/// the turns (and `approach`, for a team that has it).
pub const ROLE_BANNED: u8 = 1 << FORWARD | 1 << TURN_LEFT | 1 << TURN_RIGHT;

/// What a robot that does not chase may not choose under
/// [`DecisionConfig::support_only`]: [`ROLE_BANNED`] and `stay`.
pub const SUPPORT_ONLY_BANNED: u8 = ROLE_BANNED | 1 << STAY;

/// What no robot may choose under [`DecisionConfig::approach_only`]:
/// `forward` and the turns, the bits of [`ROLE_BANNED`].
pub const APPROACH_ONLY_BANNED: u8 = ROLE_BANNED;

/// The actions, beyond a `shoot` out of reach, that the robot that received
/// `obs` may not choose now under `decision`, as bits (`1 << index`):
/// `pass` without a receiver or out of reach (`in_reach`, from the
/// encoder); [`ROLE_BANNED`] (and `approach`) for a robot that is not a
/// chaser under [`DecisionConfig::chasers`] ([`SUPPORT_ONLY_BANNED`] with
/// [`DecisionConfig::support_only`]); [`APPROACH_ONLY_BANNED`] for every
/// robot under [`DecisionConfig::approach_only`]; `forward` and `shoot`
/// where [`DecisionConfig::own_goal_guard`] holds.
pub fn banned_actions(obs: &Observation, in_reach: bool, decision: &DecisionConfig) -> u8 {
    let mut banned = decision.own_goal_guard.map_or(0, |g| g.banned(obs));
    if decision.pass && !pass_possible(obs, in_reach) {
        banned |= 1 << PASS;
    }
    if decision.approach_only {
        banned |= APPROACH_ONLY_BANNED;
    }
    if decision.chasers > 0 && !is_chaser(obs, decision.chasers) {
        banned |= if decision.support_only {
            SUPPORT_ONLY_BANNED
        } else {
            ROLE_BANNED
        };
        if decision.approach {
            banned |= 1 << APPROACH;
        }
    }
    banned
}

/// The uniform number in [0, 1) a sampling robot uses at `tick`: a hash of
/// the match seed, the robot's team and player and the tick, so it does not
/// depend on how robots are batched or in which order they are asked.
pub fn sample_uniform(match_seed: u64, team: usize, player: usize, tick: Tick) -> f32 {
    let mut z = match_seed ^ 0x6A09_E667_F3BC_C909;
    for v in [team as u64, player as u64, tick.get()] {
        z = z.wrapping_add(v).wrapping_add(0x9E37_79B9_7F4A_7C15);
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
    }
    (z >> 40) as f32 / (1u64 << 24) as f32
}

/// Inverse-CDF sampling from a probability row with a uniform `u` in [0, 1).
pub fn sample(probs: &[f32], u: f32) -> usize {
    let total: f32 = probs.iter().sum();
    let mut acc = 0.0;
    for (i, p) in probs.iter().enumerate() {
        acc += p / total;
        if u < acc {
            return i;
        }
    }
    probs.len() - 1
}

/// Index of the largest value; the first on ties.
pub fn argmax(v: &[f32]) -> usize {
    let mut best = 0;
    for (i, x) in v.iter().enumerate() {
        if *x > v[best] {
            best = i;
        }
    }
    best
}

/// Additive logit masks for `n` rows: 0, or [`MASKED_LOGIT`] on `shoot`
/// where `shoot_ok` is false.
pub fn shoot_mask(shoot_ok: &[bool]) -> Vec<f32> {
    action_mask(shoot_ok, &[], ACTIONS)
}

/// The bans of row `i` of `banned` ([`banned_actions`]) for rows of
/// `actions` actions: a row beyond `banned` may not `pass`.
pub fn row_bans(banned: &[u8], i: usize, actions: usize) -> u8 {
    let missing = if actions > PASS { 1 << PASS } else { 0 };
    banned.get(i).copied().unwrap_or(missing)
}

/// Adds [`MASKED_LOGIT`] to the entries of `row` (one row of logits) that
/// `bans` ([`banned_actions`]) bans.
pub fn mask_row(row: &mut [f32], bans: u8) {
    for (a, x) in row.iter_mut().enumerate().take(8) {
        if bans & (1 << a) != 0 {
            *x += MASKED_LOGIT;
        }
    }
}

/// Additive logit masks for rows of `actions` logits: [`MASKED_LOGIT`] on
/// `shoot` where `shoot_ok` is false and on what `banned` bans
/// ([`banned_actions`]; a row beyond it may not `pass`).
pub fn action_mask(shoot_ok: &[bool], banned: &[u8], actions: usize) -> Vec<f32> {
    let mut m = vec![0.0; shoot_ok.len() * actions];
    for (i, (&ok, row)) in shoot_ok.iter().zip(m.chunks_exact_mut(actions)).enumerate() {
        if !ok {
            row[SHOOT] = MASKED_LOGIT;
        }
        mask_row(row, row_bans(banned, i, actions));
    }
    m
}

/// One robot's decision state in the decision-level MDP (`team` preset):
/// the action it holds and until which tick. The trainer and
/// [`crate::LearnedPolicy`] both use it, so a team decides in play exactly
/// when it decided in training, in process or over the socket.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Hold {
    action: usize,
    until: Tick,
    last_tick: Option<Tick>,
    /// A `support` held to its spot ([`DecisionConfig::support_hold`]):
    /// from this tick on it also ends on arrival or with the ball near.
    release_from: Option<Tick>,
    /// The pitch's half length and half width (m), and where the spot is.
    half: [f32; 2],
    spot: SupportSpot,
}

impl Hold {
    /// Whether the robot that received `obs` decides now: it is free to act
    /// (not lying, not busy in a kick) and its last decision's persistence
    /// has run out (for a `support` held to its spot: also once it arrived
    /// or the ball came near). A tick earlier than the last one seen is a
    /// new match.
    pub fn must_decide(&mut self, obs: &Observation) -> bool {
        if self.last_tick.is_some_and(|t| obs.tick < t) {
            *self = Hold::default();
        }
        self.last_tick = Some(obs.tick);
        if !is_free(obs) {
            return false;
        }
        if obs.tick >= self.until {
            return true;
        }
        match self.release_from {
            Some(from) if obs.tick >= from => {
                let me = obs.me();
                let spot = support_spot(obs, self.half, self.spot);
                let arrived = (spot[0] - me.x).hypot(spot[1] - me.y) <= SUPPORT_ARRIVE;
                let ball_near =
                    (obs.ball.x - me.x).hypot(obs.ball.y - me.y) <= SUPPORT_RELEASE_BALL;
                arrived || ball_near
            }
            _ => false,
        }
    }

    /// The action of a robot that does not decide now: what it holds while
    /// free, `stay` while lying or kicking (its action is ignored then).
    pub fn held(&self, obs: &Observation) -> usize {
        if is_free(obs) {
            self.action
        } else {
            STAY
        }
    }

    /// Records a decision at `tick` under `decision`, on a pitch of half
    /// length and half width `half` (m): a movement lasts `persist` ticks, a
    /// `shoot` or `pass` one (the kick then keeps the robot busy), a
    /// `support` with `support_hold` until its robot arrives, the ball
    /// comes near or `support_hold` ticks pass.
    pub fn start(&mut self, action: usize, tick: Tick, decision: &DecisionConfig, half: [f32; 2]) {
        self.action = action;
        let persist = u64::from(decision.persist.max(1));
        self.release_from = None;
        let ticks = if action == SHOOT || action == PASS {
            1
        } else if action == SUPPORT && u64::from(decision.support_hold) > persist {
            self.release_from = Some(tick + persist);
            self.half = half;
            self.spot = decision.support_spot;
            u64::from(decision.support_hold)
        } else {
            persist
        };
        self.until = tick + ticks;
    }

    /// Forgets the hold (the episode ended).
    pub fn reset(&mut self) {
        *self = Hold::default();
    }
}

/// Not lying and not in a kick.
pub fn is_free(obs: &Observation) -> bool {
    let me = obs.me();
    !me.fallen && !me.busy
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn argmax_takes_the_first_of_ties() {
        assert_eq!(argmax(&[0.0, 3.0, 3.0, -1.0]), 1);
    }

    #[test]
    fn sampling_follows_the_cumulative_distribution() {
        let p = [0.1, 0.2, 0.3, 0.4, 0.0];
        assert_eq!(sample(&p, 0.0), 0);
        assert_eq!(sample(&p, 0.05), 0);
        assert_eq!(sample(&p, 0.15), 1);
        assert_eq!(sample(&p, 0.45), 2);
        assert_eq!(sample(&p, 0.99), 3);
        // Unnormalised rows are normalised first.
        assert_eq!(sample(&[2.0, 2.0], 0.49), 0);
        assert_eq!(sample(&[2.0, 2.0], 0.51), 1);
    }

    #[test]
    fn draws_are_uniform_and_keyed_by_seed_team_player_and_tick() {
        let mut sum = 0.0f64;
        for t in 0..10_000 {
            let u = sample_uniform(3, 0, 1, Tick::new(t));
            assert!((0.0..1.0).contains(&u));
            sum += f64::from(u);
        }
        assert!((sum / 10_000.0 - 0.5).abs() < 0.02);
        let u = sample_uniform(3, 0, 1, Tick::new(5));
        assert_ne!(u, sample_uniform(4, 0, 1, Tick::new(5)));
        assert_ne!(u, sample_uniform(3, 1, 1, Tick::new(5)));
        assert_ne!(u, sample_uniform(3, 0, 2, Tick::new(5)));
        assert_ne!(u, sample_uniform(3, 0, 1, Tick::new(6)));
    }
}
