//! DQN in two presets.
//!
//! `paper` is the paper's Algorithm 1: a 5-layer fully connected Q-network
//! with ReLU between layers and one Q-value per action, experience replay, a
//! target network copied every fixed number of gradient steps, MSE loss on
//! `r + gamma max_a' Q_target(s', a') (1 - done)`, a fixed epsilon-greedy
//! exploration, per-robot parameters `theta_n`.
//!
//! `team` is the same learner with what makes DQN work in practice: Double
//! DQN (the online network picks the next action, the target network values
//! it), n-step returns, Huber loss, gradient-norm clipping, an epsilon that
//! falls linearly, and one network shared by the team (which tells robots
//! apart by the id one-hot in the observation).
//!
//! Every transition carries its own discount, `gamma^dt` for a decision that
//! lasted `dt` control ticks, so the same code serves an MDP in which robots
//! decide every tick (`dt = 1`) and one in which a decision lasts until the
//! robot is free again. An n-step return multiplies the discounts of its
//! steps: `R = r_0 + g_0 r_1 + g_0 g_1 r_2 + ...`, bootstrapped with
//! `g_0 g_1 ... g_{n-1} Q(s_n, .)`, and with nothing once the episode ended.

use rand::Rng;
use rand_chacha::ChaCha8Rng;
use tch::nn::{self, OptimizerConfig};
use tch::{Kind, Tensor};

use crate::config::DqnConfig;
use crate::nets::QNet;
use crate::obs::OBS_DIM;
use crate::LearnError;
use naosoccer_policy::actions::{ACTIONS, SHOOT};

/// The paper's TD target `r + gamma max_a' Q_target(s', a') (1 - done)`;
/// `q_next_target` is `[n, ACTIONS]`.
pub fn td_target(rewards: &Tensor, q_next_target: &Tensor, dones: &Tensor, gamma: f64) -> Tensor {
    let max_next = q_next_target.max_dim(1, false).0;
    rewards + gamma * max_next * (1.0 - dones)
}

/// The TD target with a discount per transition: `r + g Q_target(s', a*)`,
/// where `g` is the transition's bootstrap discount (`gamma^dt`, the product
/// of its steps' discounts for an n-step return, 0 once the episode ended)
/// and `a*` is the target network's best action, or with `q_next_online`
/// (Double DQN) the online network's.
///
/// `next_mask` (`[n, ACTIONS]`, added to both networks' values) rules out
/// actions impossible in `s'`: [`MASKED_Q`] on `shoot` while the ball is out
/// of reach, 0 elsewhere.
pub fn td_target_discounted(
    returns: &Tensor,
    discounts: &Tensor,
    q_next_target: &Tensor,
    q_next_online: Option<&Tensor>,
    next_mask: Option<&Tensor>,
) -> Tensor {
    let masked = |q: &Tensor| match next_mask {
        Some(m) => q + m,
        None => q.shallow_clone(),
    };
    let target = masked(q_next_target);
    let next = match q_next_online {
        Some(online) => {
            let best = masked(online).argmax(1, true);
            target.gather(1, &best, false).squeeze_dim(1)
        }
        None => target.max_dim(1, false).0,
    };
    returns + next * discounts
}

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
    len: usize,
    next: usize,
    obs: Vec<f32>,
    next_obs: Vec<f32>,
    actions: Vec<i64>,
    /// Returns (the reward, or an n-step sum).
    rewards: Vec<f32>,
    /// Bootstrap discounts: `gamma^dt` (products for n-step), 0 at episode end.
    discounts: Vec<f32>,
    /// Whether `shoot` is possible in `next_obs` (always, without a mask).
    next_ok: Vec<bool>,
}

impl Replay {
    pub fn new(cap: usize) -> Replay {
        Replay {
            cap,
            len: 0,
            next: 0,
            obs: vec![0.0; cap * OBS_DIM],
            next_obs: vec![0.0; cap * OBS_DIM],
            actions: vec![0; cap],
            rewards: vec![0.0; cap],
            discounts: vec![0.0; cap],
            next_ok: vec![true; cap],
        }
    }

    pub fn len(&self) -> usize {
        self.len
    }

    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// One transition: `reward` is its (n-step) return and `discount` what
    /// multiplies `Q(next_obs, .)` in its target (0 when the episode ended).
    pub fn push(
        &mut self,
        obs: &[f32],
        action: usize,
        reward: f32,
        next_obs: &[f32],
        discount: f32,
        next_shoot_ok: bool,
    ) {
        let i = self.next;
        self.obs[i * OBS_DIM..(i + 1) * OBS_DIM].copy_from_slice(obs);
        self.next_obs[i * OBS_DIM..(i + 1) * OBS_DIM].copy_from_slice(next_obs);
        self.actions[i] = action as i64;
        self.rewards[i] = reward;
        self.discounts[i] = discount;
        self.next_ok[i] = next_shoot_ok;
        self.next = (i + 1) % self.cap;
        self.len = (self.len + 1).min(self.cap);
    }

    /// A uniform minibatch: (obs, actions, returns, next_obs, discounts,
    /// the additive mask of `next_obs`'s actions).
    fn sample(
        &self,
        batch: usize,
        rng: &mut ChaCha8Rng,
        scratch: &mut Scratch,
    ) -> (Tensor, Tensor, Tensor, Tensor, Tensor, Tensor) {
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
            scratch.mask.resize(row + ACTIONS, 0.0);
            if !self.next_ok[i] {
                scratch.mask[row + SHOOT] = MASKED_Q;
            }
        }
        let shape = [batch as i64, OBS_DIM as i64];
        (
            Tensor::from_slice(&scratch.obs).view(shape),
            Tensor::from_slice(&scratch.actions),
            Tensor::from_slice(&scratch.rewards),
            Tensor::from_slice(&scratch.next_obs).view(shape),
            Tensor::from_slice(&scratch.discounts),
            Tensor::from_slice(&scratch.mask).view([batch as i64, ACTIONS as i64]),
        )
    }
}

#[derive(Default)]
struct Scratch {
    obs: Vec<f32>,
    next_obs: Vec<f32>,
    actions: Vec<i64>,
    rewards: Vec<f32>,
    discounts: Vec<f32>,
    mask: Vec<f32>,
    q: Vec<f32>,
    rows: Vec<f32>,
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

/// The DQN learner for a team's learning robots.
pub struct Dqn {
    pub cfg: DqnConfig,
    /// One per learning robot, or one shared.
    pub nets: Vec<QNet>,
    targets: Vec<QNet>,
    opts: Vec<nn::Optimizer>,
    replays: Vec<Replay>,
    grad_steps: Vec<usize>,
    scratch: Scratch,
}

impl Dqn {
    /// `robots`: how many learning robots a match has (one net each unless
    /// shared); `input`: the observation layout's length.
    pub fn new(cfg: DqnConfig, robots: usize, input: usize) -> Result<Dqn, LearnError> {
        let n = if cfg.shared { 1 } else { robots };
        let mut nets = Vec::with_capacity(n);
        let mut targets = Vec::with_capacity(n);
        let mut opts = Vec::with_capacity(n);
        for i in 0..n {
            let net = QNet::with_input(input, &cfg.hidden, &format!("q{i}"));
            let mut target = QNet::with_input(input, &cfg.hidden, &format!("q{i}"));
            target.vs.copy(&net.vs)?;
            opts.push(nn::Adam::default().build(&net.vs, cfg.lr)?);
            nets.push(net);
            targets.push(target);
        }
        Ok(Dqn {
            replays: (0..n).map(|_| Replay::new(cfg.replay)).collect(),
            grad_steps: vec![0; n],
            cfg,
            nets,
            targets,
            opts,
            scratch: Scratch::default(),
        })
    }

    /// Which network robot slot `k` (0..robots) uses.
    pub fn net_of(&self, k: usize) -> usize {
        if self.cfg.shared {
            0
        } else {
            k
        }
    }

    /// Epsilon-greedy actions for `n` robots; row `i` belongs to learning
    /// robot `i % robots`. One forward pass per network over all its rows.
    pub fn act(
        &mut self,
        obs: &[f32],
        robots: usize,
        epsilon: f64,
        rng: &mut ChaCha8Rng,
        actions: &mut [usize],
    ) {
        let n = actions.len();
        greedy_actions(
            &self.nets,
            self.cfg.shared,
            obs,
            robots,
            &mut self.scratch.rows,
            &mut self.scratch.q,
            actions,
        );
        for a in actions.iter_mut().take(n) {
            if rng.random::<f64>() < epsilon {
                *a = rng.random_range(0..ACTIONS);
            }
        }
    }

    /// Stores one (n-step) transition of learning robot slot `k`; see
    /// [`Replay::push`].
    #[allow(clippy::too_many_arguments)]
    pub fn remember(
        &mut self,
        k: usize,
        obs: &[f32],
        action: usize,
        reward: f32,
        next_obs: &[f32],
        discount: f32,
        next_shoot_ok: bool,
    ) {
        let i = self.net_of(k);
        self.replays[i].push(obs, action, reward, next_obs, discount, next_shoot_ok);
    }

    /// The greedy Q-values of every row (`[n, ACTIONS]` into `q`); row `i`
    /// is learning robot `i % robots`.
    pub fn q_values(&mut self, obs: &[f32], robots: usize, q: &mut Vec<f32>) {
        let n = obs.len() / OBS_DIM;
        q.resize(n * ACTIONS, 0.0);
        for (k, net) in self.nets.iter().enumerate() {
            let mine: Vec<usize> = if self.cfg.shared || self.nets.len() == 1 {
                (0..n).collect()
            } else {
                (0..n).filter(|i| i % robots == k).collect()
            };
            if mine.is_empty() {
                continue;
            }
            self.scratch.rows.clear();
            for &i in &mine {
                self.scratch
                    .rows
                    .extend_from_slice(&obs[i * OBS_DIM..(i + 1) * OBS_DIM]);
            }
            let m = mine.len();
            let x = Tensor::from_slice(&self.scratch.rows).view([m as i64, OBS_DIM as i64]);
            let y = tch::no_grad(|| net.q(&x));
            self.scratch.q.resize(m * ACTIONS, 0.0);
            y.copy_data(&mut self.scratch.q, m * ACTIONS);
            for (j, &i) in mine.iter().enumerate() {
                q[i * ACTIONS..(i + 1) * ACTIONS]
                    .copy_from_slice(&self.scratch.q[j * ACTIONS..(j + 1) * ACTIONS]);
            }
            if self.cfg.shared || self.nets.len() == 1 {
                break;
            }
        }
    }

    /// Gradient steps on every network whose buffer is past warm-up; returns
    /// the mean loss of the steps taken, if any.
    pub fn learn(&mut self, rng: &mut ChaCha8Rng) -> Option<f64> {
        let mut total = 0.0;
        let mut count = 0;
        for i in 0..self.nets.len() {
            if self.replays[i].len() < self.cfg.warmup.max(self.cfg.batch) {
                continue;
            }
            for _ in 0..self.cfg.updates_per_step {
                let (o, a, r, o2, d, mask) =
                    self.replays[i].sample(self.cfg.batch, rng, &mut self.scratch);
                let q = self.nets[i]
                    .q(&o)
                    .gather(1, &a.unsqueeze(1), false)
                    .squeeze_dim(1);
                let y = tch::no_grad(|| {
                    let online = self.cfg.double.then(|| self.nets[i].q(&o2));
                    td_target_discounted(
                        &r,
                        &d,
                        &self.targets[i].q(&o2),
                        online.as_ref(),
                        Some(&mask),
                    )
                });
                let loss = if self.cfg.huber {
                    q.smooth_l1_loss(&y, tch::Reduction::Mean, 1.0)
                } else {
                    (&q - &y).square().mean(Kind::Float)
                };
                if self.cfg.max_grad_norm > 0.0 {
                    self.opts[i].backward_step_clip_norm(&loss, self.cfg.max_grad_norm);
                } else {
                    self.opts[i].backward_step(&loss);
                }
                total += f64::try_from(&loss).unwrap_or(f64::NAN);
                count += 1;
                self.grad_steps[i] += 1;
                if self.grad_steps[i].is_multiple_of(self.cfg.target_every.max(1)) {
                    // The copy cannot fail: both stores hold the same variables.
                    let _ = self.targets[i].vs.copy(&self.nets[i].vs);
                }
            }
        }
        (count > 0).then(|| total / f64::from(count))
    }
}

/// Greedy actions from Q-networks: row `i` of `obs` is learning robot
/// `i % robots`; with per-robot networks the rows of each robot are gathered
/// and evaluated in one forward pass.
pub(crate) fn greedy_actions(
    nets: &[QNet],
    shared: bool,
    obs: &[f32],
    robots: usize,
    rows: &mut Vec<f32>,
    q: &mut Vec<f32>,
    actions: &mut [usize],
) {
    let n = actions.len();
    if shared || nets.len() == 1 {
        forward_argmax(&nets[0], obs, n, q, actions);
        return;
    }
    let per = n / robots;
    let mut acts = vec![0usize; per];
    for (k, net) in nets.iter().enumerate().take(robots) {
        rows.clear();
        for j in 0..per {
            let i = j * robots + k;
            rows.extend_from_slice(&obs[i * OBS_DIM..(i + 1) * OBS_DIM]);
        }
        forward_argmax(net, rows, per, q, &mut acts);
        for j in 0..per {
            actions[j * robots + k] = acts[j];
        }
    }
}

fn forward_argmax(net: &QNet, obs: &[f32], n: usize, q: &mut Vec<f32>, out: &mut [usize]) {
    let x = Tensor::from_slice(&obs[..n * OBS_DIM]).view([n as i64, OBS_DIM as i64]);
    let qs = tch::no_grad(|| net.q(&x));
    q.resize(n * ACTIONS, 0.0);
    qs.copy_data(q, n * ACTIONS);
    for (i, o) in out.iter_mut().enumerate().take(n) {
        *o = argmax(&q[i * ACTIONS..(i + 1) * ACTIONS]);
    }
}

/// An epsilon-greedy choice from one row of Q-values: with probability
/// `epsilon` a uniformly random allowed action, else the best allowed one
/// (`shoot` is allowed when `shoot_ok`).
pub fn epsilon_greedy(q: &[f32], shoot_ok: bool, epsilon: f64, rng: &mut ChaCha8Rng) -> usize {
    if rng.random::<f64>() < epsilon {
        let a = rng.random_range(0..ACTIONS - usize::from(!shoot_ok));
        // Without shoot, the draw skips its index.
        return if !shoot_ok && a >= SHOOT { a + 1 } else { a };
    }
    let mut best = 0; // forward: never the masked shoot
    for (i, &x) in q.iter().enumerate() {
        if (i != SHOOT || shoot_ok) && x > q[best] {
            best = i;
        }
    }
    best
}

pub use naosoccer_policy::actions::argmax;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::DqnPreset;

    #[test]
    fn td_target_is_reward_plus_discounted_max_unless_done() {
        let r = Tensor::from_slice(&[1.0f32, 0.5, -1.0]);
        let q = Tensor::from_slice(&[
            0.0f32, 2.0, 1.0, 0.0, 0.0, -1.0, -3.0, -2.0, -5.0, -4.0, 10.0, 0.0, 0.0, 0.0, 0.0,
        ])
        .view([3, 5]);
        let d = Tensor::from_slice(&[0.0f32, 0.0, 1.0]);
        let y = td_target(&r, &q, &d, 0.9);
        let mut v = [0.0f32; 3];
        y.copy_data(&mut v, 3);
        // 1 + 0.9 * 2; 0.5 + 0.9 * (-1); terminal: the reward alone.
        let expected = [2.8, 0.5 - 0.9, -1.0];
        for (a, b) in v.iter().zip(expected) {
            assert!((a - b).abs() < 1e-6, "{v:?} vs {expected:?}");
        }
    }

    #[test]
    fn the_q_network_has_five_linear_layers() {
        let net = QNet::with_input(OBS_DIM, &DqnConfig::default().hidden, "q0");
        let mut names: Vec<String> = net
            .vs
            .variables()
            .into_keys()
            .filter(|k| k.ends_with("weight"))
            .collect();
        names.sort();
        assert_eq!(
            names,
            [
                "q0.l0.weight",
                "q0.l1.weight",
                "q0.l2.weight",
                "q0.l3.weight",
                "q0.l4.weight"
            ]
        );
    }

    #[test]
    fn replay_overwrites_the_oldest_transition() {
        let mut r = Replay::new(2);
        let o = [0.0; OBS_DIM];
        for a in 0..3 {
            r.push(&o, a, a as f32, &o, 0.99, true);
        }
        assert_eq!(r.len(), 2);
        assert_eq!(r.actions, vec![2, 1]);
    }

    fn values(t: &Tensor) -> Vec<f32> {
        let n = t.numel();
        let mut v = vec![0.0f32; n];
        t.copy_data(&mut v, n);
        v
    }

    #[test]
    fn the_paper_target_is_the_discounted_target_with_gamma_until_done() {
        let r = Tensor::from_slice(&[1.0f32, 0.5, -1.0]);
        let q = Tensor::from_slice(&[
            0.0f32, 2.0, 1.0, 0.0, 0.0, -1.0, -3.0, -2.0, -5.0, -4.0, 10.0, 0.0, 0.0, 0.0, 0.0,
        ])
        .view([3, 5]);
        let d = Tensor::from_slice(&[0.0f32, 0.0, 1.0]);
        let g = Tensor::from_slice(&[0.99f32, 0.99, 0.0]);
        assert_eq!(
            values(&td_target(&r, &q, &d, 0.99)),
            values(&td_target_discounted(&r, &g, &q, None, None))
        );
    }

    #[test]
    fn double_dqn_values_the_online_choice_with_the_target_network() {
        let r = Tensor::from_slice(&[1.0f32, 0.0, 2.0]);
        // Per-transition discounts: gamma^dt for dt = 1, 3 and a finished episode.
        let g = Tensor::from_slice(&[0.9f32, 0.729, 0.0]);
        let target = Tensor::from_slice(&[
            5.0f32, 1.0, 0.0, 0.0, 0.0, // max 5 at action 0
            0.0, 0.0, 7.0, 2.0, 0.0, // max 7 at action 2
            9.0, 9.0, 9.0, 9.0, 9.0,
        ])
        .view([3, 5]);
        let online = Tensor::from_slice(&[
            0.0f32, 3.0, 0.0, 0.0, 0.0, // picks action 1
            0.0, 0.0, 0.0, 4.0, 0.0, // picks action 3
            1.0, 0.0, 0.0, 0.0, 0.0,
        ])
        .view([3, 5]);
        let y = values(&td_target_discounted(&r, &g, &target, Some(&online), None));
        // Double: target's value of the online argmax, not the target's max.
        let expected = [1.0 + 0.9 * 1.0, 0.729 * 2.0, 2.0];
        for (a, b) in y.iter().zip(expected) {
            assert!((a - b).abs() < 1e-6, "{y:?} vs {expected:?}");
        }
        let plain = values(&td_target_discounted(&r, &g, &target, None, None));
        let expected = [1.0 + 0.9 * 5.0, 0.729 * 7.0, 2.0];
        for (a, b) in plain.iter().zip(expected) {
            assert!((a - b).abs() < 1e-6, "{plain:?} vs {expected:?}");
        }
    }

    #[test]
    fn masked_next_actions_are_neither_chosen_nor_valued() {
        let r = Tensor::from_slice(&[0.0f32, 0.0]);
        let g = Tensor::from_slice(&[1.0f32, 1.0]);
        // Shoot (index 3) is the best next action of both rows, by both nets.
        let q = Tensor::from_slice(&[
            1.0f32, 0.0, 0.0, 9.0, 0.0, //
            0.0, 2.0, 0.0, 9.0, 0.0,
        ])
        .view([2, 5]);
        // Row 0: the ball is out of reach in s'; row 1: in reach.
        let mut m = vec![0.0f32; 10];
        m[SHOOT] = MASKED_Q;
        let mask = Tensor::from_slice(&m).view([2, 5]);
        assert_eq!(
            values(&td_target_discounted(&r, &g, &q, Some(&q), Some(&mask))),
            [1.0, 9.0]
        );
        assert_eq!(
            values(&td_target_discounted(&r, &g, &q, None, Some(&mask))),
            [1.0, 9.0]
        );
        // A finished episode bootstraps nothing, masked or not.
        let done = Tensor::from_slice(&[0.0f32, 0.0]);
        assert_eq!(
            values(&td_target_discounted(&r, &done, &q, None, Some(&mask))),
            [0.0, 0.0]
        );
    }

    #[test]
    fn epsilon_greedy_never_picks_a_masked_shoot() {
        use rand::SeedableRng;
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let q = [0.0f32, 1.0, 0.0, 5.0, 0.0];
        assert_eq!(epsilon_greedy(&q, true, 0.0, &mut rng), SHOOT);
        assert_eq!(epsilon_greedy(&q, false, 0.0, &mut rng), 1);
        let mut seen = [0usize; ACTIONS];
        for _ in 0..2000 {
            seen[epsilon_greedy(&q, false, 1.0, &mut rng)] += 1;
        }
        assert_eq!(seen[SHOOT], 0, "{seen:?}");
        assert!(
            seen.iter().enumerate().all(|(i, &c)| i == SHOOT || c > 400),
            "{seen:?}"
        );
        let mut seen = [0usize; ACTIONS];
        for _ in 0..2000 {
            seen[epsilon_greedy(&q, true, 1.0, &mut rng)] += 1;
        }
        assert!(seen.iter().all(|&c| c > 300), "{seen:?}");
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

    #[test]
    fn epsilon_falls_linearly_then_stays() {
        let mut c = DqnConfig::team();
        c.epsilon_start = 1.0;
        c.epsilon = 0.1;
        c.epsilon_decay = 1000;
        assert_eq!(c.epsilon_at(0), 1.0);
        assert!((c.epsilon_at(500) - 0.55).abs() < 1e-12);
        assert!((c.epsilon_at(900) - 0.19).abs() < 1e-12);
        assert_eq!(c.epsilon_at(1000), 0.1);
        assert_eq!(c.epsilon_at(10_000_000), 0.1);
        // The paper's is fixed.
        let p = DqnConfig::paper();
        assert_eq!((p.epsilon_at(0), p.epsilon_at(5_000_000)), (0.3, 0.3));
        assert!((DqnConfig::team().discount(3) - 0.995f32.powi(3)).abs() < 1e-7);
    }

    #[test]
    fn configurations_without_the_new_fields_load_as_the_paper() {
        // A DQN section as the shipped dqn-seed* runs wrote it.
        let old = r#"{"gamma":0.99,"lr":0.001,"epsilon":0.3,"hidden":[128,128,128,128],
            "replay":100000,"batch":128,"warmup":1000,"target_every":1000,
            "updates_per_step":1,"shared":false}"#;
        let c: DqnConfig = serde_json::from_str(old).unwrap();
        assert_eq!(c, DqnConfig::paper());
        assert_eq!("team".parse::<DqnPreset>(), Ok(DqnPreset::Team));
        assert!("rainbow".parse::<DqnPreset>().is_err());
    }

    #[test]
    fn argmax_takes_the_first_of_ties() {
        assert_eq!(argmax(&[0.0, 3.0, 3.0, -1.0]), 1);
    }
}
