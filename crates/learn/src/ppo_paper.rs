//! PPO with every robot deciding every tick: the paper's Algorithm 2
//! (`paper` preset: discounted returns, normalised, `A = R_norm - V(s)`, `K`
//! epochs over the whole batch) and CleanRL's `ppo.py` (`cleanrl` preset:
//! GAE bootstrapped at the rollout's end, minibatches). They share the
//! networks and the clipped surrogate with the `team` preset's learner
//! ([`crate::ppo`]); what differs (the rollout, the estimators, acting
//! without masks, the update, the loop) is here.

use std::path::Path;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use tch::nn::{self, OptimizerConfig};
use tch::{Kind, Tensor};

use crate::config::{run_scale, PpoConfig, Preset, TrainConfig};
use crate::metrics::Progress;
use crate::ppo::{accumulate, clipped_surrogate_loss, sample, shuffle, Ppo, UpdateStats, ACTIONS};
use crate::run::{make_env, Run, TrainSummary};
use crate::LearnError;

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

impl Ppo {
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
        let x = self.net.actor_input(obs, n);
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
        let x = self.net.actor_input(obs, n);
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
        let obs = self.net.actor_input(&ro.obs, n);
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
            Preset::Cleanrl | Preset::Team => {
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
            ..UpdateStats::default()
        }
    }
}

/// Trains a per-tick PPO run (`paper` or `cleanrl` preset): every robot
/// decides every tick; an update after each rollout of `rollout` ticks.
pub fn train(
    cfg: &TrainConfig,
    out: &Path,
    progress: &mut dyn FnMut(&Progress<'_>),
) -> Result<TrainSummary, LearnError> {
    let mut env = make_env(cfg)?;
    let mut ppo = Ppo::new(cfg.ppo.clone(), &run_scale(cfg), cfg.learners.len())?;
    let mut rng = ChaCha8Rng::seed_from_u64(cfg.seed);
    let mut run = Run::start(cfg, out, &mut env, &[&ppo.net.vs], false, progress)?;
    let rows = env.rows();
    let mut ro = Rollout::default();
    let (mut actions, mut logp, mut values, mut last_values) = (
        vec![0usize; rows],
        vec![0.0f32; rows],
        vec![0.0f32; rows],
        vec![0.0f32; rows],
    );
    while !run.done() {
        ro.clear();
        for _ in 0..cfg.ppo.rollout {
            ro.obs.extend_from_slice(env.observations());
            let obs = env.observations();
            ppo.act(obs, &mut rng, &mut actions, &mut logp, &mut values);
            let finished = env.step(&actions)?;
            ro.actions.extend(actions.iter().map(|&a| a as i64));
            ro.logp.extend_from_slice(&logp);
            ro.values.extend_from_slice(&values);
            ro.rewards.extend_from_slice(env.rewards());
            ro.dones
                .extend(env.dones().iter().map(|&d| f32::from(u8::from(d))));
            run.observe(env.rewards(), finished);
        }
        ppo.values(env.observations(), &mut last_values);
        let stats = ppo.update(&ro, rows, &last_values, &mut rng);
        let before = run.count(cfg.ppo.rollout * rows);
        run.log(&env, (stats.policy_loss, stats.value_loss, stats.entropy))?;
        run.refresh_opponents(before, &mut env, &[&ppo.net.vs])?;
        if run.checkpoint_due() {
            run.checkpoint(&[&ppo.net.vs])?;
        }
    }
    run.finish(&[&ppo.net.vs])
}

/// The per-tick presets' optimiser: tch's Adam with the actor's and the
/// critic's learning rates (and CleanRL's epsilon for `cleanrl`).
pub(crate) fn optimiser(cfg: &PpoConfig, vs: &nn::VarStore) -> Result<nn::Optimizer, LearnError> {
    let eps = if cfg.preset == Preset::Cleanrl {
        1e-5
    } else {
        1e-8
    };
    let mut opt = nn::Adam {
        eps,
        ..Default::default()
    }
    .build(vs, cfg.lr_actor)?;
    opt.set_lr_group(0, cfg.lr_actor);
    opt.set_lr_group(1, cfg.lr_critic);
    Ok(opt)
}

#[cfg(test)]
mod tests {
    use super::*;

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
}
