//! Policies map an observation to an action. One file per built-in policy.

use std::fmt;
use std::str::FromStr;

use naosoccer_proto::{Action, Observation, RobotId};

pub mod idle;
pub mod random;
pub mod scripted;

pub use idle::Idle;
pub use random::RandomPolicy;
pub use scripted::{Scripted, ScriptedParams};

/// Decides one robot's action from its observation, every control tick.
///
/// A policy object may drive several robots of one team (a team client): it
/// then receives their observations together in `act_batch`, which learned
/// policies override to run one batched forward pass.
pub trait Policy: Send {
    /// The action for the robot that received `obs`.
    fn act(&mut self, obs: &Observation) -> Action;

    /// The actions for several robots of one team, in order.
    fn act_batch(&mut self, obs: &[Observation], out: &mut [Action]) {
        for (o, a) in obs.iter().zip(out.iter_mut()) {
            *a = self.act(o);
        }
    }

    /// A short name for logs and statistics.
    fn name(&self) -> &str;
}

/// The built-in policies, as named on the command line.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PolicyKind {
    /// The paper's rule-based team: face the ball, approach, control, shoot
    /// when the distance and angle conditions hold; player 0 keeps goal.
    Scripted,
    /// A uniformly random action every tick, from a per-robot seeded stream.
    Random,
    /// `stay`, always.
    Idle,
}

impl PolicyKind {
    /// The policy for one robot. Every player gets its own instance, built
    /// with the match seed and its robot id; the server and the in-process
    /// runner both follow this rule, so they play the same match.
    pub fn build(&self, seed: u64, robot: RobotId) -> Box<dyn Policy> {
        match self {
            PolicyKind::Scripted => Box::new(Scripted::new(ScriptedParams::default())),
            PolicyKind::Random => Box::new(RandomPolicy::new(seed, robot)),
            PolicyKind::Idle => Box::new(Idle),
        }
    }

    pub fn name(&self) -> &'static str {
        match self {
            PolicyKind::Scripted => "scripted",
            PolicyKind::Random => "random",
            PolicyKind::Idle => "idle",
        }
    }
}

impl fmt::Display for PolicyKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// A policy name that is not one of the built-in ones.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("unknown policy {name:?} (expected scripted, random or idle)")]
#[non_exhaustive]
pub struct ParsePolicyError {
    pub name: String,
}

impl FromStr for PolicyKind {
    type Err = ParsePolicyError;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s {
            "scripted" => Ok(PolicyKind::Scripted),
            "random" => Ok(PolicyKind::Random),
            "idle" => Ok(PolicyKind::Idle),
            other => Err(ParsePolicyError {
                name: other.to_string(),
            }),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip() {
        for k in [PolicyKind::Scripted, PolicyKind::Random, PolicyKind::Idle] {
            assert_eq!(k.to_string().parse::<PolicyKind>(), Ok(k));
        }
        let err = "ppo".parse::<PolicyKind>().unwrap_err();
        assert!(err.to_string().contains("ppo"));
    }
}
