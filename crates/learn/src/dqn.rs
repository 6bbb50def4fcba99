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
//!
//! Under the decision-level MDP the network has one output per action of
//! the run's [`naosoccer_policy::DecisionConfig`] (the paper's five, up to
//! nine with `pass`, `support`, `approach` and `defend`, as PPO's `team`
//! actor), and both acting and the target keep to the actions allowed in
//! the state: not banned ([`naosoccer_policy::actions::banned_actions`])
//! and `shoot` only in reach ([`allowed_actions`]).
//!
//! Both presets run one loop over the decision-level MDP
//! ([`crate::env::decisions`]): in `paper` every robot decides every tick,
//! unmasked, and each decision lasts that tick; in `team` a robot decides
//! when it is free to act.
//!
//! Read top to bottom: the loop ([`train`]), acting ([`epsilon_greedy`]
//! over [`Dqn::q_values`]), storing ([`Dqn::remember`], into
//! [`crate::replay`]) and the update ([`Dqn::learn`], its target
//! [`td_target_discounted`]). The run directory, metrics, opponents and
//! checkpoints are the harness's ([`crate::run`]).

use std::path::Path;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use tch::nn::{self, OptimizerConfig};
use tch::{Kind, Tensor};

use crate::config::{run_scale, DqnConfig, TrainConfig};
use crate::env::decisions::{Decisions, End};
use crate::metrics::Progress;
use crate::nets::QNet;
use crate::obs::OBS_DIM;
use crate::replay::{NStep, Replay};
use crate::run::{make_env, Run, TrainSummary};
use crate::LearnError;
use naosoccer_policy::actions::{
    all_actions, allowed_actions, argmax_allowed, nth_allowed, ActionSet,
};

pub use crate::replay::MASKED_Q;

/// Trains a DQN run into `out`.
///
/// Each tick, the robots free to act whose last decision ran out decide
/// (epsilon-greedy over the actions allowed them; in the `paper` preset
/// every robot, every tick, over every action); a decision closes when the
/// robot next decides, when the episode ends, or (`paper`) at the tick's
/// end, and enters the n-step accumulator as one transition with its
/// discounted reward and discount `gamma^ticks`. A learning step follows
/// every tick in which a robot decided; a metrics row every `log_every`
/// ticks.
pub fn train(
    cfg: &TrainConfig,
    out: &Path,
    progress: &mut dyn FnMut(&Progress<'_>),
) -> Result<TrainSummary, LearnError> {
    let decision = cfg.dqn.decision;
    let mut env = make_env(cfg)?;
    let scale = run_scale(cfg);
    let robots = cfg.learners.len();
    let mut dqn = Dqn::new(cfg.dqn.clone(), robots, scale.dim())?;
    let mut rng = ChaCha8Rng::seed_from_u64(cfg.seed);
    let mut run = Run::start(cfg, out, &mut env, &dqn.stores(), false, progress)?;
    let rows = env.rows();
    let mut dec = Decisions::<()>::new(&env, decision, scale, 0, cfg.dqn.discount(1));
    let (mut q, mut chosen, mut allowed) = (Vec::new(), Vec::new(), Vec::new());
    let k = dqn.actions;
    let mut nstep = NStep::new(cfg.dqn.n_step, rows);
    let mut loss = LossMean::default();
    let mut step = 0usize;
    while !run.done() {
        let asked = dec.ask(&env);
        let any = !asked.rows.is_empty();
        if any {
            let obs = env.observations();
            dqn.q_values(obs, robots, &mut q);
            let epsilon = cfg.dqn.epsilon_at(run.transitions());
            chosen.clear();
            allowed.clear();
            let masks = asked.shoot_ok.iter().zip(&asked.banned);
            for (&r, (&ok, &bans)) in asked.rows.iter().zip(masks) {
                let may = allowed_actions(ok, bans, k);
                allowed.push(may);
                let q = &q[r * k..(r + 1) * k];
                chosen.push(epsilon_greedy(q, may, epsilon, &mut rng));
            }
            let none = vec![(); chosen.len()];
            dec.decide(&env, &chosen, &none, &mut |c| {
                // The decision that ran until now ends in this state, where
                // the robot may choose `allowed[next]`.
                let End::Decided { next: j, .. } = c.end else {
                    unreachable!("a decision closes here only by the next one")
                };
                let (r, next) = (c.row, &obs[c.row * OBS_DIM..(c.row + 1) * OBS_DIM]);
                nstep.push(r, c.obs, c.action, c.reward, c.discount, false, &mut |t| {
                    let slot = r % robots;
                    dqn.remember(slot, t.obs, t.action, t.ret, next, t.discount, allowed[j])
                });
            });
        }
        let finished = env.step(dec.actions())?;
        let now = env.observations();
        dec.observe(&env, &mut |c| {
            // A one-tick decision (`paper`) goes on from the state reached;
            // after an episode's end the next observation is never
            // bootstrapped from.
            let r = c.row;
            let (next, done) = match c.end {
                End::Tick => (&now[r * OBS_DIM..(r + 1) * OBS_DIM], false),
                _ => (c.obs, true),
            };
            nstep.push(r, c.obs, c.action, c.reward, c.discount, done, &mut |t| {
                dqn.remember(
                    r % robots,
                    t.obs,
                    t.action,
                    t.ret,
                    next,
                    t.discount,
                    all_actions(k),
                )
            });
        });
        run.observe(env.rewards(), finished);
        if any {
            loss.add(dqn.learn(&mut rng));
        }
        let before = run.count(rows);
        step += 1;
        if step.is_multiple_of(cfg.log_every.max(1)) || run.done() {
            run.log(&env, (loss.take(), f64::NAN, f64::NAN))?;
        }
        run.refresh_opponents(before, &mut env, &dqn.stores())?;
        if run.checkpoint_due() {
            run.checkpoint(&dqn.stores())?;
        }
    }
    if dqn.averaging() {
        let online = out.join("final-online.safetensors");
        crate::policy::save_stores(&dqn.online_stores(), &online)?;
    }
    run.finish(&dqn.stores())
}

/// The mean TD loss of the learning steps since the last metrics row.
#[derive(Default)]
pub(crate) struct LossMean {
    sum: f64,
    n: u32,
}

impl LossMean {
    pub(crate) fn add(&mut self, loss: Option<f64>) {
        if let Some(l) = loss {
            self.sum += l;
            self.n += 1;
        }
    }

    /// The mean (NaN when no step was taken), starting afresh.
    pub(crate) fn take(&mut self) -> f64 {
        let mean = if self.n > 0 {
            self.sum / f64::from(self.n)
        } else {
            f64::NAN
        };
        *self = LossMean::default();
        mean
    }
}

/// The paper's TD target `r + gamma max_a' Q_target(s', a') (1 - done)`;
/// `q_next_target` is `[n, actions]`.
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
/// `next_mask` (`[n, actions]`, added to both networks' values) rules out
/// the actions not allowed in `s'` ([`allowed_actions`]: `shoot` while the
/// ball is out of reach, what the decision settings ban there): [`MASKED_Q`]
/// on them, 0 elsewhere; the max (or the online argmax) is over the allowed
/// actions only.
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

/// The DQN learner for a team's learning robots.
pub struct Dqn {
    pub cfg: DqnConfig,
    /// One per learning robot, or one shared.
    pub nets: Vec<QNet>,
    targets: Vec<QNet>,
    /// The Polyak averages of `nets` ([`DqnConfig::average`]; empty
    /// without).
    averages: Vec<QNet>,
    opts: Vec<nn::Optimizer>,
    replays: Vec<Replay>,
    grad_steps: Vec<usize>,
    /// Q-values per row: the decision settings' action count
    /// ([`DqnConfig::actions`]).
    pub actions: usize,
    /// Scratch rows and Q-values of forward passes.
    pub(crate) rows: Vec<f32>,
    pub(crate) q: Vec<f32>,
}

impl Dqn {
    /// `robots`: how many learning robots a match has (one net each unless
    /// shared); `input`: the observation layout's length.
    pub fn new(cfg: DqnConfig, robots: usize, input: usize) -> Result<Dqn, LearnError> {
        let n = if cfg.shared { 1 } else { robots };
        let actions = cfg.actions();
        let mut nets = Vec::with_capacity(n);
        let mut targets = Vec::with_capacity(n);
        let mut opts = Vec::with_capacity(n);
        let mut averages = Vec::new();
        if !(0.0..1.0).contains(&cfg.average) {
            return Err(LearnError::Config(format!(
                "DQN average must be in [0, 1) (0: none), not {}",
                cfg.average
            )));
        }
        for i in 0..n {
            let net = QNet::with_input(input, &cfg.hidden, actions, &format!("q{i}"));
            let mut target = QNet::with_input(input, &cfg.hidden, actions, &format!("q{i}"));
            target.vs.copy(&net.vs)?;
            opts.push(nn::Adam::default().build(&net.vs, cfg.lr)?);
            nets.push(net);
            targets.push(target);
        }
        // After every learning network is made, so that the averages'
        // initial draws (overwritten at once) take nothing from theirs.
        if cfg.average > 0.0 {
            for (i, net) in nets.iter().enumerate() {
                let mut avg = QNet::with_input(input, &cfg.hidden, actions, &format!("q{i}"));
                avg.vs.copy(&net.vs)?;
                averages.push(avg);
            }
        }
        Ok(Dqn {
            replays: (0..n).map(|_| Replay::new(cfg.replay, actions)).collect(),
            grad_steps: vec![0; n],
            actions,
            cfg,
            nets,
            targets,
            averages,
            opts,
            rows: Vec::new(),
            q: Vec::new(),
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

    /// The team's variables (what a checkpoint saves and self-play
    /// plays): the averages with [`DqnConfig::average`], else the learning
    /// networks.
    pub fn stores(&self) -> Vec<&nn::VarStore> {
        if self.averaging() {
            self.averages.iter().map(|n| &n.vs).collect()
        } else {
            self.online_stores()
        }
    }

    /// The learning networks' variables.
    pub fn online_stores(&self) -> Vec<&nn::VarStore> {
        self.nets.iter().map(|n| &n.vs).collect()
    }

    /// Whether the run keeps Polyak averages ([`DqnConfig::average`]).
    pub fn averaging(&self) -> bool {
        !self.averages.is_empty()
    }

    /// Stores one (n-step) transition of learning robot slot `k`, with the
    /// actions allowed in `next_obs` (all of them, [`all_actions`], without
    /// masks); see [`Replay::push`].
    #[allow(clippy::too_many_arguments)]
    pub fn remember(
        &mut self,
        k: usize,
        obs: &[f32],
        action: usize,
        reward: f32,
        next_obs: &[f32],
        discount: f32,
        next_allowed: ActionSet,
    ) {
        let i = self.net_of(k);
        self.replays[i].push(obs, action, reward, next_obs, discount, next_allowed);
    }

    /// The greedy Q-values of every row (`[n, actions]` into `q`); row `i`
    /// is learning robot `i % robots`.
    pub fn q_values(&mut self, obs: &[f32], robots: usize, q: &mut Vec<f32>) {
        let n = obs.len() / OBS_DIM;
        // `w` Q-values a row (`k` below is a network's index).
        let w = self.actions;
        q.resize(n * w, 0.0);
        for (k, net) in self.nets.iter().enumerate() {
            let mine: Vec<usize> = if self.cfg.shared || self.nets.len() == 1 {
                (0..n).collect()
            } else {
                (0..n).filter(|i| i % robots == k).collect()
            };
            if mine.is_empty() {
                continue;
            }
            self.rows.clear();
            for &i in &mine {
                self.rows
                    .extend_from_slice(&obs[i * OBS_DIM..(i + 1) * OBS_DIM]);
            }
            let m = mine.len();
            let x = Tensor::from_slice(&self.rows).view([m as i64, OBS_DIM as i64]);
            let y = tch::no_grad(|| net.q(&x));
            self.q.resize(m * w, 0.0);
            y.copy_data(&mut self.q, m * w);
            for (j, &i) in mine.iter().enumerate() {
                q[i * w..(i + 1) * w].copy_from_slice(&self.q[j * w..(j + 1) * w]);
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
                let (o, a, r, o2, d, mask) = self.replays[i].sample(self.cfg.batch, rng);
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
                if let Some(avg) = self.averages.get(i) {
                    polyak(&avg.vs, &self.nets[i].vs, self.cfg.average);
                }
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

/// `avg <- keep * avg + (1 - keep) * net`, variable by variable (both
/// stores hold the same variables, made in the same order).
fn polyak(avg: &nn::VarStore, net: &nn::VarStore, keep: f64) {
    let (a, n) = (avg.trainable_variables(), net.trainable_variables());
    debug_assert_eq!(a.len(), n.len());
    tch::no_grad(|| {
        for (mut a, n) in a.into_iter().zip(n) {
            let _ = a.lerp_(&n, 1.0 - keep);
        }
    });
}

/// An epsilon-greedy choice from one row of Q-values (one per action):
/// with probability `epsilon` a uniformly random action of `allowed`
/// ([`allowed_actions`]), else the allowed one of the largest value (the
/// first on ties). With nothing allowed, any action.
///
/// The random draw is one `random_range(0..count)` over the allowed
/// actions in index order, so a five-action team whose only mask is
/// `shoot`'s draws as it always did (the draw skipping a masked `shoot`).
pub fn epsilon_greedy(q: &[f32], allowed: ActionSet, epsilon: f64, rng: &mut ChaCha8Rng) -> usize {
    let all = all_actions(q.len());
    let allowed = match allowed & all {
        0 => all,
        a => a,
    };
    if rng.random::<f64>() < epsilon {
        let k = rng.random_range(0..allowed.count_ones() as usize);
        return nth_allowed(allowed, k);
    }
    argmax_allowed(q, allowed)
}

pub use naosoccer_policy::actions::argmax;

#[cfg(test)]
mod tests;
