//! The players: the `Policy` trait, the built-in teams and trained teams,
//! without libtorch: everything playing a `naosoccer train` run needs, and
//! nothing training needs.
//!
//! - [`bots`]: the [`Policy`] trait and the built-in teams (the scripted
//!   ladder, random, idle) with their specs ([`PolicyKind`]).
//! - [`obs`]: the observation vector (versioned layout, see docs/LEARNING.md).
//! - [`actions`]: the action table, the decision-level MDP's holds, the
//!   sampling draws.
//! - [`mlp`]: the networks' forward pass in plain Rust, read from the
//!   safetensors checkpoints the trainer writes.
//! - [`learned`]: a trained team as the client's `Policy`
//!   ([`load_policy`]), and as a batch player of many matches at once.
//! - [`guard`]: the own-goal guard a trained team may play with.
//! - [`export`]: a PPO actor trained elsewhere (Python) written as a team
//!   directory that `ppo:DIR` plays.
//!
//! Many matches (evaluations, leagues, the academy) are crates/eval's, which
//! plays these players. crates/learn (tch) trains the networks and depends
//! on this crate; this crate never depends on it, so every command that
//! only plays links no libtorch.

pub mod actions;
pub mod bots;
mod error;
pub mod export;
pub mod guard;
pub mod learned;
pub mod mlp;
pub mod obs;

use naosoccer_proto::Observation;

pub use actions::{
    approach_action, support_action, to_action, DecisionConfig, NetAction, SupportSpot, ACTIONS,
    MAX_ACTIONS,
};
pub use bots::{
    is_builtin_spec, Idle, ParsePolicyError, Policy, PolicyKind, RandomPolicy, Scripted,
    ScriptedParams,
};
pub use error::PolicyError;
pub use guard::OwnGoalGuard;
pub use learned::{
    is_learned_spec, load_policy, load_policy_for_match, ActMode, Algo, LearnedPolicy, PlayConfig,
};
pub use mlp::{Activation, Mlp, Weights};
pub use obs::{ObsScale, OBS_DIM, OBS_VERSION, OBS_VERSION_LATEST};

/// Picks actions for whole teams of many matches at once.
pub trait BatchActor: Send {
    /// `teams[i]` is one match's team: the match seed (which keys sampling
    /// and per-robot decision state) and its robots' observations in player
    /// order. `out` gets one action index per observation, in order.
    fn act_teams(&mut self, teams: &[(u64, &[Observation])], out: &mut [usize]);

    /// The protocol action that action index `index` is for a robot
    /// observing `obs`, as this team plays it (its own support spot).
    fn action(&self, index: usize, obs: &Observation) -> naosoccer_proto::Action;
}

impl BatchActor for LearnedPolicy {
    fn act_teams(&mut self, teams: &[(u64, &[Observation])], out: &mut [usize]) {
        self.act_matches(teams, out);
    }

    fn action(&self, index: usize, obs: &Observation) -> naosoccer_proto::Action {
        LearnedPolicy::action(self, index, obs)
    }
}
