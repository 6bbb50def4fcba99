//! Stands still: an empty slot, or a control in experiments.

use naosoccer_proto::{Action, Observation};

use super::Policy;

#[derive(Debug, Clone, Copy, Default)]
pub struct Idle;

impl Policy for Idle {
    fn act(&mut self, _obs: &Observation) -> Action {
        Action::Stay
    }

    fn name(&self) -> &str {
        "idle"
    }
}
