//! DQN as the paper's Algorithm 1: a 5-layer fully connected Q-network with
//! ReLU between layers and one Q-value per action, experience replay, a target
//! network copied every fixed number of gradient steps, MSE loss on
//! `r + gamma max_a' Q_target(s', a') (1 - done)`, epsilon-greedy exploration.
//! Per-robot parameters `theta_n` (the paper) or one network shared by the
//! team, which then tells robots apart by the id one-hot in the observation.

use rand::Rng;
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};
use tch::nn::{self, OptimizerConfig};
use tch::{Kind, Tensor};

use crate::nets::{Activation, InitScheme, Mlp};
use crate::obs::OBS_DIM;
use crate::ppo::ACTIONS;
use crate::LearnError;

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DqnConfig {
    pub gamma: f64,
    pub lr: f64,
    /// Probability of a uniformly random action (the paper keeps it fixed).
    pub epsilon: f64,
    /// Hidden widths: four hidden layers make the paper's five linear layers.
    pub hidden: Vec<usize>,
    /// Transitions each replay buffer keeps.
    pub replay: usize,
    pub batch: usize,
    /// Transitions in a buffer before learning starts.
    pub warmup: usize,
    /// Gradient steps between copies to the target network.
    pub target_every: usize,
    /// Gradient steps per network for every vectorised environment step.
    pub updates_per_step: usize,
    /// One network for the team instead of one per robot.
    pub shared: bool,
}

impl Default for DqnConfig {
    fn default() -> Self {
        DqnConfig {
            gamma: 0.99,
            lr: 1e-3,
            epsilon: 0.3,
            hidden: vec![128, 128, 128, 128],
            replay: 100_000,
            batch: 128,
            warmup: 1_000,
            target_every: 1_000,
            updates_per_step: 1,
            shared: false,
        }
    }
}

/// The TD target `r + gamma max_a' Q_target(s', a') (1 - done)`;
/// `q_next_target` is `[n, ACTIONS]`.
pub fn td_target(rewards: &Tensor, q_next_target: &Tensor, dones: &Tensor, gamma: f64) -> Tensor {
    let max_next = q_next_target.max_dim(1, false).0;
    rewards + gamma * max_next * (1.0 - dones)
}

/// A Q-network: `OBS_DIM -> hidden x4 -> ACTIONS`.
pub struct QNet {
    pub vs: nn::VarStore,
    mlp: Mlp,
}

impl QNet {
    /// `name` prefixes the variables (`q0.l0.weight`, ...), so several
    /// networks can share one checkpoint file.
    pub fn new(hidden: &[usize], name: &str) -> QNet {
        QNet::with_input(OBS_DIM, hidden, name)
    }

    /// A network reading `input` features (an older observation layout's
    /// length, for the shipped teams).
    pub fn with_input(input: usize, hidden: &[usize], name: &str) -> QNet {
        let vs = nn::VarStore::new(tch::Device::Cpu);
        let mlp = Mlp::new(
            &(vs.root() / name),
            input,
            hidden,
            ACTIONS,
            Activation::Relu,
            InitScheme::Default,
        );
        QNet { vs, mlp }
    }

    pub fn q(&self, obs: &Tensor) -> Tensor {
        self.mlp.forward(obs)
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
    rewards: Vec<f32>,
    dones: Vec<f32>,
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
            dones: vec![0.0; cap],
        }
    }

    pub fn len(&self) -> usize {
        self.len
    }

    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    pub fn push(&mut self, obs: &[f32], action: usize, reward: f32, next_obs: &[f32], done: bool) {
        let i = self.next;
        self.obs[i * OBS_DIM..(i + 1) * OBS_DIM].copy_from_slice(obs);
        self.next_obs[i * OBS_DIM..(i + 1) * OBS_DIM].copy_from_slice(next_obs);
        self.actions[i] = action as i64;
        self.rewards[i] = reward;
        self.dones[i] = f32::from(u8::from(done));
        self.next = (i + 1) % self.cap;
        self.len = (self.len + 1).min(self.cap);
    }

    /// A uniform minibatch: (obs, actions, rewards, next_obs, dones).
    fn sample(
        &self,
        batch: usize,
        rng: &mut ChaCha8Rng,
        scratch: &mut Scratch,
    ) -> (Tensor, Tensor, Tensor, Tensor, Tensor) {
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
            scratch.dones.push(self.dones[i]);
        }
        let shape = [batch as i64, OBS_DIM as i64];
        (
            Tensor::from_slice(&scratch.obs).view(shape),
            Tensor::from_slice(&scratch.actions),
            Tensor::from_slice(&scratch.rewards),
            Tensor::from_slice(&scratch.next_obs).view(shape),
            Tensor::from_slice(&scratch.dones),
        )
    }
}

#[derive(Default)]
struct Scratch {
    obs: Vec<f32>,
    next_obs: Vec<f32>,
    actions: Vec<i64>,
    rewards: Vec<f32>,
    dones: Vec<f32>,
    q: Vec<f32>,
    rows: Vec<f32>,
}

impl Scratch {
    fn clear(&mut self) {
        self.obs.clear();
        self.next_obs.clear();
        self.actions.clear();
        self.rewards.clear();
        self.dones.clear();
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
    /// `robots`: how many learning robots a match has (one net each unless shared).
    pub fn new(cfg: DqnConfig, robots: usize) -> Result<Dqn, LearnError> {
        let n = if cfg.shared { 1 } else { robots };
        let mut nets = Vec::with_capacity(n);
        let mut targets = Vec::with_capacity(n);
        let mut opts = Vec::with_capacity(n);
        for i in 0..n {
            let net = QNet::new(&cfg.hidden, &format!("q{i}"));
            let mut target = QNet::new(&cfg.hidden, &format!("q{i}"));
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

    /// Stores one transition of learning robot slot `k`.
    pub fn remember(
        &mut self,
        k: usize,
        obs: &[f32],
        action: usize,
        reward: f32,
        next_obs: &[f32],
        done: bool,
    ) {
        let i = self.net_of(k);
        self.replays[i].push(obs, action, reward, next_obs, done);
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
                let (o, a, r, o2, d) =
                    self.replays[i].sample(self.cfg.batch, rng, &mut self.scratch);
                let q = self.nets[i]
                    .q(&o)
                    .gather(1, &a.unsqueeze(1), false)
                    .squeeze_dim(1);
                let y = tch::no_grad(|| td_target(&r, &self.targets[i].q(&o2), &d, self.cfg.gamma));
                let loss = (&q - &y).square().mean(Kind::Float);
                self.opts[i].backward_step(&loss);
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
        let net = QNet::new(&DqnConfig::default().hidden, "q0");
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
            r.push(&o, a, a as f32, &o, false);
        }
        assert_eq!(r.len(), 2);
        assert_eq!(r.actions, vec![2, 1]);
    }

    #[test]
    fn argmax_takes_the_first_of_ties() {
        assert_eq!(argmax(&[0.0, 3.0, 3.0, -1.0]), 1);
    }
}
