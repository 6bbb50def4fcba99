//! Policies map an observation to an action. One file per built-in policy.

use naosoccer_proto::{Action, Observation};

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
    Scripted,
    Random,
    Idle,
}
