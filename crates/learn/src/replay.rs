//! What DQN stores: each robot's stream of transitions turned into n-step
//! transitions ([`NStep`]), and the replay ring they are sampled from
//! ([`Replay`]), as cleanrl's `dqn.py` takes its buffer from a library.
//! Every transition carries its own bootstrap discount (`gamma^dt` for a
//! decision that lasted `dt` ticks, a product over an n-step return's
//! steps, 0 once the episode ended) and the actions allowed in its next
//! state, the only ones its target bootstraps over.

use rand::Rng;
use rand_chacha::ChaCha8Rng;
use tch::Tensor;

use crate::obs::OBS_DIM;
use naosoccer_policy::actions::{all_actions, ActionSet};

/// What a masked action's Q-value becomes: never the largest, and (times a
/// discount of 0 at an episode's end) still finite.
pub const MASKED_Q: f32 = -1e9;

/// Turns each row's stream of one-step transitions into n-step transitions:
/// once a row holds `n` steps its oldest leaves, carrying the discounted sum
/// of the `n` rewards and the product of their discounts; when an episode
/// ends every pending step leaves with the rest of its return and a
/// bootstrap discount of 0.
pub struct NStep {
    n: usize,
    rows: Vec<NStepRow>,
}

struct NStepRow {
    /// Ring of the last `n` observations, actions, rewards and discounts.
    obs: Vec<f32>,
    actions: Vec<usize>,
    rewards: Vec<f32>,
    discounts: Vec<f32>,
    start: usize,
    len: usize,
}

/// A transition ready for the replay buffer.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NStepOut<'a> {
    pub obs: &'a [f32],
    pub action: usize,
    /// `r_0 + g_0 r_1 + g_0 g_1 r_2 + ...`
    pub ret: f32,
    /// `g_0 g_1 ... g_{k-1}`, or 0 when the episode ended within the k steps.
    pub discount: f32,
}

impl NStep {
    pub fn new(n: usize, rows: usize) -> NStep {
        let n = n.max(1);
        NStep {
            n,
            rows: (0..rows)
                .map(|_| NStepRow {
                    obs: vec![0.0; n * OBS_DIM],
                    actions: vec![0; n],
                    rewards: vec![0.0; n],
                    discounts: vec![0.0; n],
                    start: 0,
                    len: 0,
                })
                .collect(),
        }
    }

    /// Adds row `row`'s step (`obs`, `action`) that earned `reward`, lasted
    /// with discount `discount` and ended the episode if `done`; calls `emit`
    /// with each transition that is complete, and the observation to
    /// bootstrap from (`next_obs`; unused when the discount is 0).
    #[allow(clippy::too_many_arguments)]
    pub fn push(
        &mut self,
        row: usize,
        obs: &[f32],
        action: usize,
        reward: f32,
        discount: f32,
        done: bool,
        emit: &mut dyn FnMut(NStepOut<'_>),
    ) {
        let n = self.n;
        let r = &mut self.rows[row];
        let slot = (r.start + r.len) % n;
        r.obs[slot * OBS_DIM..(slot + 1) * OBS_DIM].copy_from_slice(obs);
        r.actions[slot] = action;
        r.rewards[slot] = reward;
        r.discounts[slot] = discount;
        r.len += 1;
        if done {
            while r.len > 0 {
                r.emit_front(n, true, emit);
            }
            r.start = 0;
        } else if r.len == n {
            r.emit_front(n, false, emit);
        }
    }
}

impl NStepRow {
    fn emit_front(&mut self, n: usize, terminal: bool, emit: &mut dyn FnMut(NStepOut<'_>)) {
        let (mut ret, mut disc) = (0.0f32, 1.0f32);
        for j in 0..self.len {
            let k = (self.start + j) % n;
            ret += disc * self.rewards[k];
            disc *= self.discounts[k];
        }
        let s = self.start;
        emit(NStepOut {
            obs: &self.obs[s * OBS_DIM..(s + 1) * OBS_DIM],
            action: self.actions[s],
            ret,
            discount: if terminal { 0.0 } else { disc },
        });
        self.start = (s + 1) % n;
        self.len -= 1;
    }
}

/// A ring buffer of transitions.
pub struct Replay {
    cap: usize,
    /// Q-values per row (the network's actions).
    width: usize,
    len: usize,
    next: usize,
    obs: Vec<f32>,
    next_obs: Vec<f32>,
    actions: Vec<i64>,
    /// Returns (the reward, or an n-step sum).
    rewards: Vec<f32>,
    /// Bootstrap discounts: `gamma^dt` (products for n-step), 0 at episode end.
    discounts: Vec<f32>,
    /// The actions allowed in `next_obs`
    /// ([`naosoccer_policy::actions::allowed_actions`]; all without masks).
    next_allowed: Vec<ActionSet>,
    scratch: Scratch,
}

impl Replay {
    /// Room for `cap` transitions of a network with `actions` Q-values.
    pub fn new(cap: usize, actions: usize) -> Replay {
        Replay {
            cap,
            width: actions,
            len: 0,
            next: 0,
            obs: vec![0.0; cap * OBS_DIM],
            next_obs: vec![0.0; cap * OBS_DIM],
            actions: vec![0; cap],
            rewards: vec![0.0; cap],
            discounts: vec![0.0; cap],
            next_allowed: vec![all_actions(actions); cap],
            scratch: Scratch::default(),
        }
    }

    pub fn len(&self) -> usize {
        self.len
    }

    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// One transition: `reward` is its (n-step) return, `discount` what
    /// multiplies `Q(next_obs, .)` in its target (0 when the episode ended)
    /// and `next_allowed` the actions that target may take in `next_obs`.
    pub fn push(
        &mut self,
        obs: &[f32],
        action: usize,
        reward: f32,
        next_obs: &[f32],
        discount: f32,
        next_allowed: ActionSet,
    ) {
        let i = self.next;
        self.obs[i * OBS_DIM..(i + 1) * OBS_DIM].copy_from_slice(obs);
        self.next_obs[i * OBS_DIM..(i + 1) * OBS_DIM].copy_from_slice(next_obs);
        self.actions[i] = action as i64;
        self.rewards[i] = reward;
        self.discounts[i] = discount;
        self.next_allowed[i] = next_allowed;
        self.next = (i + 1) % self.cap;
        self.len = (self.len + 1).min(self.cap);
    }

    /// A uniform minibatch: (obs, actions, returns, next_obs, discounts,
    /// the additive mask of `next_obs`'s actions: [`MASKED_Q`] on those not
    /// allowed, 0 elsewhere).
    pub(crate) fn sample(
        &mut self,
        batch: usize,
        rng: &mut ChaCha8Rng,
    ) -> (Tensor, Tensor, Tensor, Tensor, Tensor, Tensor) {
        let scratch = &mut self.scratch;
        scratch.clear();
        for _ in 0..batch {
            let i = rng.random_range(0..self.len);
            scratch
                .obs
                .extend_from_slice(&self.obs[i * OBS_DIM..(i + 1) * OBS_DIM]);
            scratch
                .next_obs
                .extend_from_slice(&self.next_obs[i * OBS_DIM..(i + 1) * OBS_DIM]);
            scratch.actions.push(self.actions[i]);
            scratch.rewards.push(self.rewards[i]);
            scratch.discounts.push(self.discounts[i]);
            let row = scratch.mask.len();
            scratch.mask.resize(row + self.width, 0.0);
            for (a, m) in scratch.mask[row..].iter_mut().enumerate() {
                if self.next_allowed[i] & (1 << a) == 0 {
                    *m = MASKED_Q;
                }
            }
        }
        let shape = [batch as i64, OBS_DIM as i64];
        (
            Tensor::from_slice(&scratch.obs).view(shape),
            Tensor::from_slice(&scratch.actions),
            Tensor::from_slice(&scratch.rewards),
            Tensor::from_slice(&scratch.next_obs).view(shape),
            Tensor::from_slice(&scratch.discounts),
            Tensor::from_slice(&scratch.mask).view([batch as i64, self.width as i64]),
        )
    }
}

/// A minibatch as it is gathered, before it becomes tensors.
#[derive(Default)]
struct Scratch {
    obs: Vec<f32>,
    next_obs: Vec<f32>,
    actions: Vec<i64>,
    rewards: Vec<f32>,
    discounts: Vec<f32>,
    mask: Vec<f32>,
}

impl Scratch {
    fn clear(&mut self) {
        self.obs.clear();
        self.next_obs.clear();
        self.actions.clear();
        self.rewards.clear();
        self.discounts.clear();
        self.mask.clear();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn replay_overwrites_the_oldest_transition() {
        let mut r = Replay::new(2, 5);
        let o = [0.0; OBS_DIM];
        for a in 0..3 {
            r.push(&o, a, a as f32, &o, 0.99, all_actions(5));
        }
        assert_eq!(r.len(), 2);
        assert_eq!(r.actions, vec![2, 1]);
    }

    /// Obs rows marked by their first feature.
    fn marked(x: f32) -> Vec<f32> {
        let mut o = vec![0.0; OBS_DIM];
        o[0] = x;
        o
    }

    fn collect(
        ns: &mut NStep,
        row: usize,
        step: (f32, usize, f32, f32, bool),
    ) -> Vec<(f32, usize, f32, f32)> {
        let mut out = Vec::new();
        ns.push(
            row,
            &marked(step.0),
            step.1,
            step.2,
            step.3,
            step.4,
            &mut |t| out.push((t.obs[0], t.action, t.ret, t.discount)),
        );
        out
    }

    #[test]
    fn n_step_returns_multiply_varying_discounts_and_stop_at_the_episode_end() {
        let mut ns = NStep::new(3, 2);
        // Row 0: steps with discounts 0.9, 0.5, 0.8 (decisions of unequal length).
        assert!(collect(&mut ns, 0, (10.0, 1, 1.0, 0.9, false)).is_empty());
        assert!(collect(&mut ns, 0, (11.0, 2, 2.0, 0.5, false)).is_empty());
        // Row 1 is independent of row 0.
        assert!(collect(&mut ns, 1, (50.0, 0, 100.0, 0.1, false)).is_empty());
        let out = collect(&mut ns, 0, (12.0, 3, 4.0, 0.8, false));
        // R = 1 + 0.9*2 + 0.9*0.5*4 = 4.6, bootstrap discount 0.9*0.5*0.8 = 0.36.
        assert_eq!(out.len(), 1);
        let (o, a, ret, disc) = out[0];
        assert_eq!((o, a), (10.0, 1));
        assert!(
            (ret - 4.6).abs() < 1e-6 && (disc - 0.36).abs() < 1e-6,
            "{out:?}"
        );
        // The episode ends: the three pending steps leave with what is left
        // of their returns and nothing to bootstrap.
        let out = collect(&mut ns, 0, (13.0, 4, 8.0, 0.7, true));
        assert_eq!(out.len(), 3, "{out:?}");
        let expected = [
            (11.0, 2, 2.0 + 0.5 * 4.0 + 0.5 * 0.8 * 8.0),
            (12.0, 3, 4.0 + 0.8 * 8.0),
            (13.0, 4, 8.0),
        ];
        for ((o, a, ret, disc), (eo, ea, er)) in out.iter().zip(expected) {
            assert_eq!((*o, *a, *disc), (eo, ea, 0.0));
            assert!((ret - er).abs() < 1e-5, "{out:?}");
        }
        // A new episode starts empty.
        assert!(collect(&mut ns, 0, (20.0, 0, 1.0, 0.9, false)).is_empty());
        // One-step returns are the transitions themselves.
        let mut one = NStep::new(1, 1);
        assert_eq!(
            collect(&mut one, 0, (1.0, 2, 3.0, 0.99, false)),
            [(1.0, 2, 3.0, 0.99)]
        );
        assert_eq!(
            collect(&mut one, 0, (2.0, 2, 3.0, 0.99, true)),
            [(2.0, 2, 3.0, 0.0)]
        );
    }
}
