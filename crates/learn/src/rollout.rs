//! What PPO stores: a rollout of decision-level transitions, each from
//! one decision of a robot to the next (one tick long in the per-tick
//! presets), linked along each robot's stream, and the two estimators
//! [`crate::ppo`] updates with: GAE discounted by elapsed time
//! ([`Transitions::gae`]) and the paper's discounted returns
//! ([`Transitions::discounted_returns`]). DQN's counterpart is
//! [`crate::replay`].

use naosoccer_policy::actions::ActionSet;

use crate::env::decisions::{Closed, End};

/// Decision-level transitions: each spans the `dt` ticks from one decision
/// of a robot to its next (or to the episode's end, or to the rollout's
/// edge), in the order they closed.
#[derive(Debug, Default, Clone)]
pub struct Transitions {
    /// Actor rows, `OBS_DIM` wide.
    pub obs: Vec<f32>,
    /// Critic rows, `critic_dim` wide.
    pub critic_obs: Vec<f32>,
    pub actions: Vec<i64>,
    pub logp: Vec<f32>,
    pub shoot_ok: Vec<bool>,
    /// The actions banned beyond a `shoot` out of reach
    /// ([`naosoccer_policy::actions::banned_actions`]; empty without the
    /// `pass` action).
    pub banned: Vec<ActionSet>,
    /// V(s) at the decision, in return units.
    pub values: Vec<f32>,
    /// `sum_{i < dt} gamma^i r_i`: the rewards until the next decision.
    pub rewards: Vec<f32>,
    /// Ticks until the next decision.
    pub dt: Vec<u32>,
    /// The value after `dt` ticks: the next decision's V, the bootstrap V at
    /// a rollout edge, 0 after the episode's end.
    pub next_values: Vec<f32>,
    pub dones: Vec<bool>,
    /// The transition that follows this one in its robot's stream (the next
    /// decision, in this rollout).
    pub next: Vec<Option<usize>>,
}

/// What PPO keeps of a decision until it closes: the action's
/// log-probability and the critic's value where it was taken.
#[derive(Debug, Clone, Copy, Default)]
pub struct Act {
    pub logp: f32,
    pub value: f32,
}

impl Transitions {
    /// Stores a closed decision with the value after it (`next_value`) and
    /// whether its episode ended there. `link` holds each robot's last
    /// transition while its stream goes on (it ended in the next decision):
    /// this one becomes that one's successor.
    pub fn push(
        &mut self,
        c: &Closed<'_, Act>,
        next_value: f32,
        done: bool,
        link: &mut [Option<usize>],
    ) {
        let i = self.len();
        self.obs.extend_from_slice(c.obs);
        self.critic_obs.extend_from_slice(c.critic_obs);
        self.actions.push(c.action as i64);
        self.logp.push(c.payload.logp);
        self.shoot_ok.push(c.shoot_ok);
        self.banned.push(c.banned);
        self.values.push(c.payload.value);
        self.rewards.push(c.reward);
        self.dt.push(c.ticks.max(1));
        self.next_values.push(next_value);
        self.dones.push(done);
        self.next.push(None);
        if let Some(j) = link[c.row].take() {
            self.next[j] = Some(i);
        }
        if matches!(c.end, End::Decided { .. } | End::Tick) {
            link[c.row] = Some(i);
        }
    }

    pub fn len(&self) -> usize {
        self.actions.len()
    }

    pub fn is_empty(&self) -> bool {
        self.actions.is_empty()
    }

    pub fn clear(&mut self) {
        self.obs.clear();
        self.critic_obs.clear();
        self.actions.clear();
        self.logp.clear();
        self.shoot_ok.clear();
        self.banned.clear();
        self.values.clear();
        self.rewards.clear();
        self.dt.clear();
        self.next_values.clear();
        self.dones.clear();
        self.next.clear();
    }

    /// GAE over time-discounted transitions: `delta = R + gamma^dt V' (1 -
    /// done) - V`, `A = delta + (gamma lambda)^dt A_next` along each robot's
    /// chain of decisions. Returns `(advantages, returns = A + V)`.
    pub fn gae(&self, gamma: f32, lambda: f32) -> (Vec<f32>, Vec<f32>) {
        let n = self.len();
        let mut adv = vec![0.0f32; n];
        for i in (0..n).rev() {
            let dt = self.dt[i] as i32;
            let g = gamma.powi(dt);
            let live = if self.dones[i] { 0.0 } else { 1.0 };
            let delta = self.rewards[i] + g * self.next_values[i] * live - self.values[i];
            let tail = match self.next[i] {
                Some(j) if !self.dones[i] => (gamma * lambda).powi(dt) * adv[j],
                _ => 0.0,
            };
            adv[i] = delta + tail;
        }
        let ret = adv.iter().zip(&self.values).map(|(a, v)| a + v).collect();
        (adv, ret)
    }

    /// The paper's returns: `R = r + gamma^dt R_next (1 - done)` along each
    /// robot's chain of decisions, with nothing bootstrapped past the
    /// rollout's edge.
    pub fn discounted_returns(&self, gamma: f32) -> Vec<f32> {
        let mut ret = vec![0.0f32; self.len()];
        for i in (0..self.len()).rev() {
            let g = gamma.powi(self.dt[i] as i32);
            let live = if self.dones[i] { 0.0 } else { 1.0 };
            let next = self.next[i].map_or(0.0, |j| ret[j]);
            ret[i] = self.rewards[i] + g * next * live;
        }
        ret
    }
}
