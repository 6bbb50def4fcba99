//! The action table and how a network's outputs become actions: the five
//! discrete actions, the decision-level MDP's holds, the sampling draws and
//! the inverse-CDF sampler. Training (crates/learn) and play share them, so
//! a team decides in play exactly as it did in training.
//!
//! This file holds the action table, the decision-level MDP's settings and
//! the sampling draws; `steps.rs` what `support` and `approach` turn into,
//! `masks.rs` which actions a robot may choose (roles, the pass rule, the
//! logit masks) and `hold.rs` a robot's hold. All are re-exported here.

use naosoccer_proto::Tick;
use serde::{Deserialize, Serialize};

use crate::guard::OwnGoalGuard;

mod hold;
mod masks;
mod steps;

pub use hold::{is_free, Hold};
pub use masks::{
    action_mask, all_actions, allowed_actions, argmax_allowed, banned_actions, is_chaser, mask_row,
    nth_allowed, pass_possible, row_bans, shoot_mask, APPROACH_ONLY_BANNED, ROLE_BANNED,
    SUPPORT_ONLY_BANNED,
};
pub use steps::{
    approach_action, defend_action, defend_spot, give_action, give_target, support_action,
    support_spot, to_action, walk_spot, APPROACH_ALIGN, APPROACH_BEHIND, APPROACH_LATERAL,
    APPROACH_MIN_CONE, APPROACH_NEAR, DEFEND_BEHIND, DEFEND_GOAL_MIN, GIVE_MAX, GIVE_MIN,
    GIVE_RELEASE_BALL, SUPPORT_AHEAD, SUPPORT_ARRIVE, SUPPORT_FACE_CONE, SUPPORT_RELEASE_BALL,
    SUPPORT_SIDE, SUPPORT_WALK_CONE,
};

/// One output of a team's network: the protocol's actions, in
/// `proto::Action::from_index` order (forward, turn left, turn right,
/// shoot, stay, pass), then the shipped teams' two walking steps, which are
/// not protocol actions: the team's policy turns them, every tick, into the
/// `forward`, turn or `stay` that walks the robot ([`to_action`]).
///
/// A network has the first [`ACTIONS`] (the paper's five), or more: a team
/// trained with [`DecisionConfig::pass`] has `Pass`, one trained with
/// [`DecisionConfig::support`] `Support` too, one trained with
/// [`DecisionConfig::approach`] `Approach` too ([`DecisionConfig::actions`]).
/// Its output `i` is the action whose [`NetAction::index`] is `i`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Default)]
pub enum NetAction {
    /// `forward`; also what a hold that never decided holds.
    #[default]
    Forward,
    TurnLeft,
    TurnRight,
    Shoot,
    Stay,
    /// The protocol's `pass` (1.3): a kick at the receiver's feet.
    Pass,
    /// A walk to the robot's support spot ([`support_action`]).
    Support,
    /// A walk round behind the ball onto the line to the opponent goal,
    /// then into the ball ([`approach_action`]).
    Approach,
    /// A walk back onto the line from the ball to the own goal, between
    /// them ([`defend_action`]).
    Defend,
    /// A pass lined up: a walk round behind the ball onto its line to a
    /// free teammate, then the protocol's `pass` once the pass rule names a
    /// receiver ([`give_action`]).
    Give,
}

impl NetAction {
    /// Every network action, by index.
    pub const ALL: [NetAction; MAX_ACTIONS] = [
        NetAction::Forward,
        NetAction::TurnLeft,
        NetAction::TurnRight,
        NetAction::Shoot,
        NetAction::Stay,
        NetAction::Pass,
        NetAction::Support,
        NetAction::Approach,
        NetAction::Defend,
        NetAction::Give,
    ];

    /// The network output this action is.
    pub const fn index(self) -> usize {
        self as usize
    }

    /// The action of network output `index`, if there is one.
    pub fn from_index(index: usize) -> Option<NetAction> {
        NetAction::ALL.get(index).copied()
    }

    /// This action's bit in a ban set (`1 << index`, [`banned_actions`]).
    pub const fn bit(self) -> ActionSet {
        1 << self as ActionSet
    }

    /// The name the docs and the Python package use.
    pub const fn name(self) -> &'static str {
        match self {
            NetAction::Forward => "forward",
            NetAction::TurnLeft => "turn_left",
            NetAction::TurnRight => "turn_right",
            NetAction::Shoot => "shoot",
            NetAction::Stay => "stay",
            NetAction::Pass => "pass",
            NetAction::Support => "support",
            NetAction::Approach => "approach",
            NetAction::Defend => "defend",
            NetAction::Give => "give",
        }
    }

    /// Whether this is a kick (`shoot` or `pass`).
    pub const fn is_kick(self) -> bool {
        matches!(self, NetAction::Shoot | NetAction::Pass)
    }
}

/// The paper's five actions: the networks of teams without `pass`,
/// `support` or `approach` have this many outputs.
pub const ACTIONS: usize = 5;

/// The most actions a network has (the paper's five, `pass`, `support`,
/// `approach`, `defend` and `give`).
pub const MAX_ACTIONS: usize = 10;

/// A set of network actions, one bit each (`1 << index`): the bans of
/// [`banned_actions`].
pub type ActionSet = u16;

/// The actions' names, by index ([`NetAction::name`]).
pub const ACTION_NAMES: [&str; MAX_ACTIONS] = {
    let mut names = [""; MAX_ACTIONS];
    let mut i = 0;
    while i < MAX_ACTIONS {
        names[i] = NetAction::ALL[i].name();
        i += 1;
    }
    names
};

/// A logit this low makes an action impossible (its probability underflows to 0).
pub const MASKED_LOGIT: f32 = -1e9;

fn every_tick() -> u32 {
    1
}

/// The decision-level MDP (`team` presets). A setting this build does not
/// know is refused rather than ignored: a team trained with it would
/// otherwise play here without it, silently differently.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DecisionConfig {
    /// Ticks a movement decision (`forward`, turns, `stay`) lasts before the
    /// robot decides again (a `shoot` lasts as long as the kick keeps it busy).
    /// Left out (as a Python `decision` dict may): 1, every tick.
    #[serde(default = "every_tick")]
    pub persist: u32,
    /// `shoot` is impossible while the ball is out of kick reach. Left out:
    /// `false`.
    #[serde(default)]
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
    /// The robots have a ninth action, `defend` (needs `support`): walk back
    /// onto the line from the ball to the centre of the own goal, between
    /// them ([`defend_action`]), and face the ball there. Possible for every
    /// robot, chaser or not; held like `support` under `support_hold`. A
    /// team with `defend` but not `approach` has `approach`'s output too,
    /// always masked. Absent from older runs' configurations: `false`.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub defend: bool,
    /// The robots have a tenth action, `give` (needs `pass`, `support`,
    /// `approach` and `defend`): line up a pass to a free teammate and
    /// make it ([`give_action`]). Possible while [`give_target`] names a
    /// teammate; under `chasers`, only for the chasers. Held under
    /// `support_hold` until the pass is made ([`Hold`]). Absent from older
    /// runs' configurations: `false`.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub give: bool,
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
            defend: false,
            give: false,
            own_goal_guard: None,
        }
    }

    /// How many actions the networks choose among: 5, 6 with `pass`, 7
    /// with `pass` and `support`, 8 with `approach` too, 9 with `defend`
    /// (whose `approach` output is masked without `approach`), 10 with
    /// `give`.
    pub fn actions(&self) -> usize {
        if self.give {
            return NetAction::Give.index() + 1;
        }
        if self.support && self.defend {
            return NetAction::Defend.index() + 1;
        }
        match (self.pass, self.support, self.approach) {
            (_, true, true) => NetAction::Approach.index() + 1,
            (_, true, false) => NetAction::Support.index() + 1,
            (true, false, _) => NetAction::Pass.index() + 1,
            (false, false, _) => ACTIONS,
        }
    }
}

/// The number of actions of a team in `decision` (`None`: the paper's five).
pub fn action_count(decision: Option<DecisionConfig>) -> usize {
    decision.map_or(ACTIONS, |d| d.actions())
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn network_actions_are_the_protocols_then_the_walking_steps() {
        for (i, a) in NetAction::ALL.into_iter().enumerate() {
            assert_eq!(a.index(), i);
            assert_eq!(NetAction::from_index(i), Some(a));
            assert_eq!(a.bit(), 1 << i);
            assert_eq!(ACTION_NAMES[i], a.name());
        }
        assert_eq!(NetAction::from_index(MAX_ACTIONS), None);
        // The first six are the protocol's, in its order and by its names.
        for (a, p) in NetAction::ALL.into_iter().zip(naosoccer_proto::Action::ALL) {
            assert_eq!(a.index(), p.index());
            assert_eq!(a.name(), p.name());
        }
        assert!(NetAction::Shoot.is_kick() && NetAction::Pass.is_kick());
        assert!(!NetAction::Support.is_kick());
    }

    #[test]
    fn a_decision_setting_left_out_takes_its_default() {
        let d: DecisionConfig = serde_json::from_str(r#"{"pass": true}"#).unwrap();
        assert_eq!(
            (d.persist, d.mask_shoot, d.pass, d.chasers),
            (1, false, true, 0)
        );
        assert_eq!(d.actions(), 6);
        let err = serde_json::from_str::<DecisionConfig>(r#"{"persits": 3}"#).unwrap_err();
        assert!(err.to_string().contains("persits"), "{err}");
    }

    #[test]
    fn argmax_takes_the_first_of_ties() {
        assert_eq!(argmax(&[0.0, 3.0, 3.0, -1.0]), 1);
    }

    /// DQN's allowed sets: the k-th allowed action of a uniform draw is the
    /// old five-action scheme (a masked `shoot` skipped) bit for bit, and
    /// greedy choices never leave the set.
    #[test]
    fn allowed_actions_draw_and_argmax_within_the_set() {
        assert_eq!(all_actions(5), 0b1_1111);
        assert_eq!(all_actions(9), 0b1_1111_1111);
        let shoot = NetAction::Shoot.index();
        for ok in [true, false] {
            let allowed = allowed_actions(ok, 0, ACTIONS);
            let n = allowed.count_ones() as usize;
            assert_eq!(n, ACTIONS - usize::from(!ok));
            for k in 0..n {
                let old = if !ok && k >= shoot { k + 1 } else { k };
                assert_eq!(nth_allowed(allowed, k), old);
            }
        }
        // Bans beyond the row's width do not count; shoot follows shoot_ok.
        let bans = NetAction::Forward.bit() | NetAction::Pass.bit();
        let allowed = allowed_actions(false, bans, 7);
        let listed: Vec<usize> = (0..allowed.count_ones() as usize)
            .map(|k| nth_allowed(allowed, k))
            .collect();
        assert_eq!(listed, [1, 2, 4, 6]);
        let q = [9.0, 1.0, 3.0, 8.0, 3.0, 7.0, 2.0];
        assert_eq!(argmax_allowed(&q, allowed), 2, "first of the allowed ties");
        assert_eq!(argmax_allowed(&q, all_actions(7)), 0);
        assert_eq!(argmax_allowed(&q, NetAction::Support.bit()), 6);
        assert_eq!(argmax_allowed(&q, 0), 0, "nothing allowed: plain argmax");
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
