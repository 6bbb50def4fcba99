//! Which actions a robot may choose now: the roles under `chasers`, the
//! pass rule, and the logit masks built from them.

use naosoccer_proto::Observation;

use super::{ActionSet, DecisionConfig, NetAction, ACTIONS, MASKED_LOGIT};

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
pub(super) fn nearest_standing_teammate(obs: &Observation) -> Option<(f32, usize)> {
    standing_teammates(obs).fold(None, |best, (j, d)| match best {
        Some((b, _)) if b <= d => best,
        _ => Some((d, j)),
    })
}

/// The actions a robot that is not one of its team's chasers may not choose
/// under [`DecisionConfig::chasers`], as bits (`1 << index`): `forward` and
/// the turns (and `approach`, for a team that has it).
pub const ROLE_BANNED: ActionSet =
    NetAction::Forward.bit() | NetAction::TurnLeft.bit() | NetAction::TurnRight.bit();

/// What a robot that does not chase may not choose under
/// [`DecisionConfig::support_only`]: [`ROLE_BANNED`] and `stay`.
pub const SUPPORT_ONLY_BANNED: ActionSet = ROLE_BANNED | NetAction::Stay.bit();

/// What no robot may choose under [`DecisionConfig::approach_only`]:
/// `forward` and the turns, the bits of [`ROLE_BANNED`].
pub const APPROACH_ONLY_BANNED: ActionSet = ROLE_BANNED;

/// The actions, beyond a `shoot` out of reach, that the robot that received
/// `obs` may not choose now under `decision`, as bits (`1 << index`):
/// `pass` without a receiver or out of reach (`in_reach`, from the
/// encoder); [`ROLE_BANNED`] (and `approach`) for a robot that is not a
/// chaser under [`DecisionConfig::chasers`] ([`SUPPORT_ONLY_BANNED`] with
/// [`DecisionConfig::support_only`]); [`APPROACH_ONLY_BANNED`] for every
/// robot under [`DecisionConfig::approach_only`]; `approach` always for a
/// team with `defend` but not `approach`; `forward` and `shoot` where
/// [`DecisionConfig::own_goal_guard`] holds; `give` with no teammate to
/// give to ([`give_target`](super::give_target)) and, under
/// [`DecisionConfig::chasers`], for a robot that is not a chaser.
pub fn banned_actions(obs: &Observation, in_reach: bool, decision: &DecisionConfig) -> ActionSet {
    let mut banned = decision.own_goal_guard.map_or(0, |g| g.banned(obs));
    if decision.pass && !pass_possible(obs, in_reach) {
        banned |= NetAction::Pass.bit();
    }
    if decision.give && super::give_target(obs).is_none() {
        banned |= NetAction::Give.bit();
    }
    if decision.approach_only {
        banned |= APPROACH_ONLY_BANNED;
    }
    if decision.defend && !decision.approach {
        banned |= NetAction::Approach.bit();
    }
    if decision.chasers > 0 && !is_chaser(obs, decision.chasers) {
        banned |= if decision.support_only {
            SUPPORT_ONLY_BANNED
        } else {
            ROLE_BANNED
        };
        if decision.approach {
            banned |= NetAction::Approach.bit();
        }
        if decision.give {
            banned |= NetAction::Give.bit();
        }
    }
    banned
}

/// Every action of a row of `actions` outputs, as bits.
pub const fn all_actions(actions: usize) -> ActionSet {
    ((1u32 << actions) - 1) as ActionSet
}

/// The actions of a row of `actions` outputs a robot may choose, as bits:
/// those `bans` ([`banned_actions`], [`row_bans`]) does not ban, `shoot`
/// only when `shoot_ok`. What a DQN team acts (greedy or epsilon-greedy)
/// and bootstraps over.
pub fn allowed_actions(shoot_ok: bool, bans: ActionSet, actions: usize) -> ActionSet {
    let shoot = if shoot_ok { 0 } else { NetAction::Shoot.bit() };
    all_actions(actions) & !bans & !shoot
}

/// The `k`-th (from 0) action of `allowed`, by index: a uniform draw among
/// `allowed.count_ones()` values picks an allowed action uniformly. Past
/// the last: the last allowed one (`stay` when there is none).
pub fn nth_allowed(allowed: ActionSet, k: usize) -> usize {
    let mut last = NetAction::Stay.index();
    let mut seen = 0;
    for a in NetAction::ALL {
        if allowed & a.bit() != 0 {
            if seen == k {
                return a.index();
            }
            last = a.index();
            seen += 1;
        }
    }
    last
}

/// The index of the largest of the values of `q` that `allowed` allows
/// (the first on ties): a greedy DQN choice. With nothing allowed, the
/// largest of all.
pub fn argmax_allowed(q: &[f32], allowed: ActionSet) -> usize {
    let ok = |i: usize| allowed & (1 << i) != 0;
    let Some(mut best) = (0..q.len()).find(|&i| ok(i)) else {
        return super::argmax(q);
    };
    for (i, &x) in q.iter().enumerate() {
        if ok(i) && x > q[best] {
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
/// `actions` actions: a row beyond `banned` may not `pass` (nor `give`).
pub fn row_bans(banned: &[ActionSet], i: usize, actions: usize) -> ActionSet {
    let missing = [NetAction::Pass, NetAction::Give]
        .into_iter()
        .filter(|a| actions > a.index())
        .fold(0, |m, a| m | a.bit());
    banned.get(i).copied().unwrap_or(missing)
}

/// Adds [`MASKED_LOGIT`] to the entries of `row` (one row of logits) that
/// `bans` ([`banned_actions`]) bans.
pub fn mask_row(row: &mut [f32], bans: ActionSet) {
    for (x, a) in row.iter_mut().zip(NetAction::ALL) {
        if bans & a.bit() != 0 {
            *x += MASKED_LOGIT;
        }
    }
}

/// Additive logit masks for rows of `actions` logits: [`MASKED_LOGIT`] on
/// `shoot` where `shoot_ok` is false and on what `banned` bans
/// ([`banned_actions`]; a row beyond it may not `pass`).
pub fn action_mask(shoot_ok: &[bool], banned: &[ActionSet], actions: usize) -> Vec<f32> {
    let mut m = vec![0.0; shoot_ok.len() * actions];
    for (i, (&ok, row)) in shoot_ok.iter().zip(m.chunks_exact_mut(actions)).enumerate() {
        if !ok {
            row[NetAction::Shoot.index()] = MASKED_LOGIT;
        }
        mask_row(row, row_bans(banned, i, actions));
    }
    m
}
