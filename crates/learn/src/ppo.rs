//! PPO, actor-critic.
//!
//! Two presets:
//! - `paper` (default): the paper's Algorithm 2 as the widely copied
//!   PPO-PyTorch code does it — discounted returns computed backwards and
//!   normalised, `A = R_norm - V(s)`, clipped surrogate, MSE value loss,
//!   entropy bonus, `K` epochs over the full batch, Adam with separate
//!   learning rates for actor (3e-4) and critic (1e-3), 64-64 tanh networks.
//! - `cleanrl`: GAE(lambda) with a bootstrapped value at the rollout's end,
//!   per-minibatch advantage normalisation, gradient-norm clipping and
//!   orthogonal initialisation (CleanRL's `ppo.py`).

use rand::Rng;
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};
use tch::nn::{self, OptimizerConfig};
use tch::{Kind, Tensor};

use crate::nets::{Activation, InitScheme, Mlp};
use crate::obs::OBS_DIM;
use crate::LearnError;

pub const ACTIONS: usize = 5;

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum Preset {
    #[default]
    Paper,
    Cleanrl,
}

impl std::str::FromStr for Preset {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "paper" => Ok(Preset::Paper),
            "cleanrl" => Ok(Preset::Cleanrl),
            o => Err(format!(
                "unknown PPO preset {o:?} (expected paper or cleanrl)"
            )),
        }
    }
}

/// PPO's hyperparameters. `PpoConfig::paper()` and `PpoConfig::cleanrl()`
/// give the presets; docs/LEARNING.md says where each value comes from.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PpoConfig {
    pub preset: Preset,
    pub gamma: f64,
    /// GAE's lambda (cleanrl preset only).
    pub gae_lambda: f64,
    pub clip: f64,
    /// Value-loss weight `c1`.
    pub value_coef: f64,
    /// Entropy-bonus weight `c2`.
    pub entropy_coef: f64,
    pub lr_actor: f64,
    pub lr_critic: f64,
    /// Passes over each rollout.
    pub epochs: usize,
    /// Minibatches a pass is split into (1 = the full batch).
    pub minibatches: usize,
    /// Control ticks each match plays between updates.
    pub rollout: usize,
    /// Gradient-norm clip (cleanrl preset), none when `None`.
    pub max_grad_norm: Option<f64>,
    pub hidden: Vec<usize>,
}

impl PpoConfig {
    pub fn paper() -> PpoConfig {
        PpoConfig {
            preset: Preset::Paper,
            gamma: 0.99,
            gae_lambda: 1.0,
            clip: 0.2,
            value_coef: 0.5,
            entropy_coef: 0.01,
            lr_actor: 3e-4,
            lr_critic: 1e-3,
            epochs: 80,
            minibatches: 1,
            rollout: 128,
            max_grad_norm: None,
            hidden: vec![64, 64],
        }
    }

    pub fn cleanrl() -> PpoConfig {
        PpoConfig {
            preset: Preset::Cleanrl,
            gamma: 0.99,
            gae_lambda: 0.95,
            clip: 0.2,
            value_coef: 0.5,
            entropy_coef: 0.01,
            lr_actor: 2.5e-4,
            lr_critic: 2.5e-4,
            epochs: 4,
            minibatches: 4,
            rollout: 128,
            max_grad_norm: Some(0.5),
            hidden: vec![64, 64],
        }
    }

    pub fn preset(p: Preset) -> PpoConfig {
        match p {
            Preset::Paper => PpoConfig::paper(),
            Preset::Cleanrl => PpoConfig::cleanrl(),
        }
    }
}

/// The actor (action logits) and critic (state value), in one `VarStore`:
/// the actor's variables in optimiser group 0, the critic's in group 1, so
/// one Adam runs both at their own learning rates.
pub struct ActorCritic {
    pub vs: nn::VarStore,
    actor: Mlp,
    critic: Mlp,
}

impl ActorCritic {
    pub fn new(cfg: &PpoConfig) -> ActorCritic {
        let vs = nn::VarStore::new(tch::Device::Cpu);
        let (ai, ci) = match cfg.preset {
            Preset::Paper => (InitScheme::Default, InitScheme::Default),
            Preset::Cleanrl => (
                InitScheme::Orthogonal { output_gain: 0.01 },
                InitScheme::Orthogonal { output_gain: 1.0 },
            ),
        };
        let root = vs.root();
        let actor = Mlp::new(
            &(root.set_group(0) / "actor"),
            OBS_DIM,
            &cfg.hidden,
            ACTIONS,
            Activation::Tanh,
            ai,
        );
        let critic = Mlp::new(
            &(root.set_group(1) / "critic"),
            OBS_DIM,
            &cfg.hidden,
            1,
            Activation::Tanh,
            ci,
        );
        ActorCritic { vs, actor, critic }
    }

    /// Action logits, `[n, ACTIONS]`.
    pub fn logits(&self, obs: &Tensor) -> Tensor {
        self.actor.forward(obs)
    }

    /// State values, `[n]`.
    pub fn value(&self, obs: &Tensor) -> Tensor {
        self.critic.forward(obs).squeeze_dim(-1)
    }
}

/// The clipped surrogate objective, as a loss to minimise:
/// `-mean(min(ratio * A, clip(ratio, 1 - eps, 1 + eps) * A))` with
/// `ratio = exp(logp - logp_old)`.
pub fn clipped_surrogate_loss(logp: &Tensor, logp_old: &Tensor, adv: &Tensor, clip: f64) -> Tensor {
    let ratio = (logp - logp_old).exp();
    let s1 = &ratio * adv;
    let s2 = ratio.clamp(1.0 - clip, 1.0 + clip) * adv;
    -s1.min_other(&s2).mean(Kind::Float)
}

/// Discounted returns computed backwards, restarting at episode ends, for a
/// rollout stored time-major (`[t][stream]`): `R_t = r_t + gamma R_{t+1} (1 - done_t)`.
/// No bootstrap past the rollout's end (the paper's estimator).
pub fn discounted_returns(rewards: &[f32], dones: &[f32], streams: usize, gamma: f32) -> Vec<f32> {
    let steps = rewards.len() / streams;
    let mut out = vec![0.0; rewards.len()];
    let mut acc = vec![0.0f32; streams];
    for t in (0..steps).rev() {
        for (s, a) in acc.iter_mut().enumerate() {
            let i = t * streams + s;
            *a = rewards[i] + gamma * *a * (1.0 - dones[i]);
            out[i] = *a;
        }
    }
    out
}

/// Generalised advantage estimation over a time-major rollout, bootstrapped
/// with `last_values` (the values of the observations after the last step).
/// Returns `(advantages, returns = advantages + values)`.
pub fn gae(
    rewards: &[f32],
    values: &[f32],
    dones: &[f32],
    last_values: &[f32],
    gamma: f32,
    lambda: f32,
) -> (Vec<f32>, Vec<f32>) {
    let streams = last_values.len();
    let steps = rewards.len() / streams;
    let mut adv = vec![0.0; rewards.len()];
    let mut last = vec![0.0f32; streams];
    for t in (0..steps).rev() {
        for s in 0..streams {
            let i = t * streams + s;
            let next_v = if t + 1 == steps {
                last_values[s]
            } else {
                values[i + streams]
            };
            let nonterminal = 1.0 - dones[i];
            let delta = rewards[i] + gamma * next_v * nonterminal - values[i];
            last[s] = delta + gamma * lambda * nonterminal * last[s];
            adv[i] = last[s];
        }
    }
    let ret = adv.iter().zip(values).map(|(a, v)| a + v).collect();
    (adv, ret)
}

/// One rollout: every learner robot's transitions, time-major.
#[derive(Debug, Default)]
pub struct Rollout {
    pub obs: Vec<f32>,
    pub actions: Vec<i64>,
    pub logp: Vec<f32>,
    pub values: Vec<f32>,
    pub rewards: Vec<f32>,
    pub dones: Vec<f32>,
}

impl Rollout {
    pub fn clear(&mut self) {
        self.obs.clear();
        self.actions.clear();
        self.logp.clear();
        self.values.clear();
        self.rewards.clear();
        self.dones.clear();
    }
}

/// What one update reports.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct UpdateStats {
    pub policy_loss: f64,
    pub value_loss: f64,
    pub entropy: f64,
}

/// The PPO learner: networks, optimiser and the sampling RNG.
pub struct Ppo {
    pub cfg: PpoConfig,
    pub net: ActorCritic,
    opt: nn::Optimizer,
    probs: Vec<f32>,
}

impl Ppo {
    pub fn new(cfg: PpoConfig) -> Result<Ppo, LearnError> {
        let net = ActorCritic::new(&cfg);
        let eps = if cfg.preset == Preset::Cleanrl {
            1e-5
        } else {
            1e-8
        };
        let mut opt = nn::Adam {
            eps,
            ..Default::default()
        }
        .build(&net.vs, cfg.lr_actor)?;
        opt.set_lr_group(0, cfg.lr_actor);
        opt.set_lr_group(1, cfg.lr_critic);
        Ok(Ppo {
            cfg,
            net,
            opt,
            probs: Vec::new(),
        })
    }

    /// Samples one action per row of `obs` (`n` rows of `OBS_DIM`) in one
    /// forward pass; writes actions, their log-probabilities and the values.
    pub fn act(
        &mut self,
        obs: &[f32],
        rng: &mut ChaCha8Rng,
        actions: &mut [usize],
        logp: &mut [f32],
        values: &mut [f32],
    ) {
        let n = actions.len();
        let x = Tensor::from_slice(obs).view([n as i64, OBS_DIM as i64]);
        let (p, v) = tch::no_grad(|| {
            (
                self.net.logits(&x).softmax(-1, Kind::Float),
                self.net.value(&x),
            )
        });
        self.probs.resize(n * ACTIONS, 0.0);
        p.copy_data(&mut self.probs, n * ACTIONS);
        v.copy_data(values, n);
        for i in 0..n {
            let row = &self.probs[i * ACTIONS..(i + 1) * ACTIONS];
            let a = sample(row, rng.random::<f32>());
            actions[i] = a;
            logp[i] = row[a].max(1e-12).ln();
        }
    }

    /// Values of `n` observations (the bootstrap for GAE).
    pub fn values(&self, obs: &[f32], out: &mut [f32]) {
        let n = out.len();
        let x = Tensor::from_slice(obs).view([n as i64, OBS_DIM as i64]);
        tch::no_grad(|| self.net.value(&x)).copy_data(out, n);
    }

    /// One PPO update on a rollout of `streams` robots. `last_values` are the
    /// critic's values of the observations after the rollout (cleanrl only).
    pub fn update(
        &mut self,
        ro: &Rollout,
        streams: usize,
        last_values: &[f32],
        rng: &mut ChaCha8Rng,
    ) -> UpdateStats {
        let n = ro.actions.len();
        let cfg = self.cfg.clone();
        let obs = Tensor::from_slice(&ro.obs).view([n as i64, OBS_DIM as i64]);
        let actions = Tensor::from_slice(&ro.actions);
        let logp_old = Tensor::from_slice(&ro.logp);
        let mut stats = UpdateStats::default();
        let mut count = 0.0;
        match cfg.preset {
            Preset::Paper => {
                let r = discounted_returns(&ro.rewards, &ro.dones, streams, cfg.gamma as f32);
                let r = Tensor::from_slice(&r);
                let r_norm = (&r - r.mean(Kind::Float)) / (r.std(true) + 1e-7);
                for _ in 0..cfg.epochs {
                    let s = self.step(&obs, &actions, &logp_old, None, &r_norm);
                    accumulate(&mut stats, s, &mut count);
                }
            }
            Preset::Cleanrl => {
                let (adv, ret) = gae(
                    &ro.rewards,
                    &ro.values,
                    &ro.dones,
                    last_values,
                    cfg.gamma as f32,
                    cfg.gae_lambda as f32,
                );
                let adv = Tensor::from_slice(&adv);
                let ret = Tensor::from_slice(&ret);
                let mb = n.div_ceil(cfg.minibatches.max(1));
                let mut order: Vec<i64> = (0..n as i64).collect();
                for _ in 0..cfg.epochs {
                    shuffle(&mut order, rng);
                    for chunk in order.chunks(mb) {
                        let idx = Tensor::from_slice(chunk);
                        let a = adv.index_select(0, &idx);
                        let a = (&a - a.mean(Kind::Float)) / (a.std(true) + 1e-8);
                        let s = self.step(
                            &obs.index_select(0, &idx),
                            &actions.index_select(0, &idx),
                            &logp_old.index_select(0, &idx),
                            Some(&a),
                            &ret.index_select(0, &idx),
                        );
                        accumulate(&mut stats, s, &mut count);
                    }
                }
            }
        }
        if count > 0.0 {
            stats.policy_loss /= count;
            stats.value_loss /= count;
            stats.entropy /= count;
        }
        stats
    }

    /// One gradient step. Without `adv`, the advantage is `target - V(s)`
    /// with the critic's current values (the paper's `A = R_norm - V`).
    fn step(
        &mut self,
        obs: &Tensor,
        actions: &Tensor,
        logp_old: &Tensor,
        adv: Option<&Tensor>,
        target: &Tensor,
    ) -> UpdateStats {
        let logits = self.net.logits(obs);
        let logp_all = logits.log_softmax(-1, Kind::Float);
        let logp = logp_all
            .gather(1, &actions.unsqueeze(1), false)
            .squeeze_dim(1);
        let entropy = -(logp_all.exp() * &logp_all)
            .sum_dim_intlist(-1, false, Kind::Float)
            .mean(Kind::Float);
        let v = self.net.value(obs);
        let adv = match adv {
            Some(a) => a.shallow_clone(),
            None => target - v.detach(),
        };
        let pl = clipped_surrogate_loss(&logp, logp_old, &adv, self.cfg.clip);
        let vl = (&v - target).square().mean(Kind::Float);
        let loss = &pl + self.cfg.value_coef * &vl - self.cfg.entropy_coef * &entropy;
        self.opt.zero_grad();
        loss.backward();
        if let Some(m) = self.cfg.max_grad_norm {
            self.opt.clip_grad_norm(m);
        }
        self.opt.step();
        UpdateStats {
            policy_loss: f64::try_from(&pl).unwrap_or(f64::NAN),
            value_loss: f64::try_from(&vl).unwrap_or(f64::NAN),
            entropy: f64::try_from(&entropy).unwrap_or(f64::NAN),
        }
    }
}

fn accumulate(total: &mut UpdateStats, s: UpdateStats, count: &mut f64) {
    total.policy_loss += s.policy_loss;
    total.value_loss += s.value_loss;
    total.entropy += s.entropy;
    *count += 1.0;
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

/// Fisher-Yates with our own RNG, so minibatches repeat with the seed.
fn shuffle(v: &mut [i64], rng: &mut ChaCha8Rng) {
    for i in (1..v.len()).rev() {
        let j = rng.random_range(0..=i);
        v.swap(i, j);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn vals(t: &Tensor) -> Vec<f32> {
        let n = t.numel();
        let mut v = vec![0.0; n];
        t.to_kind(Kind::Float).copy_data(&mut v, n);
        v
    }

    #[test]
    fn surrogate_clips_the_ratio_on_the_side_the_advantage_favours() {
        // ratios e^0.5 = 1.65, e^-0.5 = 0.61, 1.0 and 1.1 with advantages +1, -1, +2, -1.
        let logp_old = Tensor::from_slice(&[0.0f32, 0.0, 0.0, 0.0]);
        let logp = Tensor::from_slice(&[0.5f32, -0.5, 0.0, 1.1f32.ln()]);
        let adv = Tensor::from_slice(&[1.0f32, -1.0, 2.0, -1.0]);
        let loss = vals(&clipped_surrogate_loss(&logp, &logp_old, &adv, 0.2))[0];
        // min(1.65*1, 1.2*1) = 1.2; min(0.61*-1, 0.8*-1) = -0.8; 2.0; min(-1.1, -1.1) = -1.1.
        let expected = -(1.2 - 0.8 + 2.0 - 1.1) / 4.0;
        assert!((loss - expected).abs() < 1e-5, "{loss} vs {expected}");
    }

    #[test]
    fn surrogate_gradient_vanishes_once_clipped() {
        let logp = Tensor::from_slice(&[0.5f32]).set_requires_grad(true);
        let loss = clipped_surrogate_loss(
            &logp,
            &Tensor::from_slice(&[0.0f32]),
            &Tensor::from_slice(&[1.0f32]),
            0.2,
        );
        loss.backward();
        assert_eq!(vals(&logp.grad()), vec![0.0]);
        let logp = Tensor::from_slice(&[0.1f32]).set_requires_grad(true);
        let loss = clipped_surrogate_loss(
            &logp,
            &Tensor::from_slice(&[0.0f32]),
            &Tensor::from_slice(&[1.0f32]),
            0.2,
        );
        loss.backward();
        // d(-ratio)/dlogp = -ratio inside the clip range.
        assert!((vals(&logp.grad())[0] + 0.1f32.exp()).abs() < 1e-5);
    }

    #[test]
    fn returns_are_discounted_backwards_and_restart_at_episode_ends() {
        // Two streams, three steps, time-major; stream 0's episode ends at t = 1.
        let rewards = [1.0, 0.0, 1.0, 0.0, 1.0, 1.0];
        let dones = [0.0, 0.0, 1.0, 0.0, 0.0, 0.0];
        let r = discounted_returns(&rewards, &dones, 2, 0.5);
        // Stream 0: 1 + 0.5 * 1, then 1 (its episode ends), 1; stream 1: 0.25, 0.5, 1.
        assert_eq!(r, vec![1.5, 0.25, 1.0, 0.5, 1.0, 1.0]);
    }

    #[test]
    fn gae_with_lambda_one_is_the_bootstrapped_return_minus_value() {
        let rewards = [1.0, 1.0];
        let values = [0.5, 0.25];
        let (adv, ret) = gae(&rewards, &values, &[0.0, 0.0], &[2.0], 0.5, 1.0);
        // R_1 = 1 + 0.5 * 2 = 2; R_0 = 1 + 0.5 * 2 = 2.
        assert_eq!(ret, vec![2.0, 2.0]);
        assert_eq!(adv, vec![1.5, 1.75]);
        // lambda = 0: one-step TD errors.
        let (adv, _) = gae(&rewards, &values, &[0.0, 1.0], &[2.0], 0.5, 0.0);
        assert_eq!(adv, vec![1.0 + 0.5 * 0.25 - 0.5, 1.0 - 0.25]);
    }

    #[test]
    fn sampling_follows_the_probabilities() {
        let p = [0.1, 0.2, 0.3, 0.4, 0.0];
        assert_eq!(sample(&p, 0.05), 0);
        assert_eq!(sample(&p, 0.25), 1);
        assert_eq!(sample(&p, 0.59), 2);
        assert_eq!(sample(&p, 0.99), 3);
    }
}
