//! PPO for a team (`team` preset): actor-critic on the decision-level MDP
//! ([`crate::env::decisions`]). A robot decides only when it is free to act,
//! movement persists, `shoot` (and what [`DecisionConfig`] bans) is masked,
//! and a transition spans the ticks from one decision to the next: returns
//! are discounted by the time that elapsed (`gamma^dt`, GAE with
//! `(gamma lambda)^dt`), bootstrapped at rollout edges and where a drill
//! cut an episode. On top of CleanRL's machinery (minibatches, per-batch
//! advantage normalisation, gradient clipping): value normalisation, a KL
//! early stop, learning-rate and entropy schedules, and an optional
//! centralised critic (MAPPO: the critic reads the whole team's
//! observation vectors).
//!
//! Read top to bottom: the loop ([`train`]), acting ([`Ppo::act_masked`],
//! [`Ppo::critic_values`]), storing ([`Transitions`]), the advantage
//! ([`Transitions::gae`]) and the update ([`Ppo::update_decisions`]). The
//! run directory, metrics, opponents and checkpoints are the harness's
//! ([`crate::run`]); the per-tick presets (`paper`, `cleanrl`) are
//! [`crate::ppo_paper`].

use std::path::Path;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use tch::nn;
use tch::{Kind, Tensor};

use crate::adam::Adam;
use crate::config::{run_scale, PpoConfig, TrainConfig};
use crate::env::decisions::{Closed, Decisions, End};
use crate::metrics::Progress;
use crate::nets::{ActorCritic, RunningNorm};
use crate::obs::ObsScale;
use crate::run::resume::{read_checkpoint, ResumeState};
use crate::run::{make_env, Run, TrainSummary};
use crate::warm_start::{init_weights, SUPPORT_INIT_BIAS};
use crate::LearnError;
use naosoccer_policy::actions::ActionSet;

pub use naosoccer_policy::actions::{
    action_count, action_mask, sample, shoot_mask, DecisionConfig, NetAction, ACTIONS,
};

/// Trains a team-preset run into `out`, or goes on from `resume` (a
/// checkpoint of the run in `out`) as if it had not stopped.
///
/// Every tick each learning robot either decides (a forward pass; its open
/// transition closes with the new decision's value) or holds its action;
/// an episode's end closes it with no bootstrap, a drill's cut and the
/// rollout's edge with the critic's value of the state reached. A rollout
/// also ends with the episodes (all matches have one length and end
/// together): checkpoints fall on episode boundaries, where a resumed run
/// can rebuild the matches exactly.
pub fn train(
    cfg: &TrainConfig,
    out: &Path,
    resume: Option<ResumeState>,
    progress: &mut dyn FnMut(&Progress<'_>),
) -> Result<TrainSummary, LearnError> {
    let decision = cfg
        .ppo
        .decision
        .ok_or_else(|| LearnError::Config("no decision configuration".into()))?;
    let mut env = make_env(cfg)?;
    let scale = run_scale(cfg);
    let mut ppo = Ppo::new(cfg.ppo.clone(), &scale, cfg.learners.len())?;
    let mut rng = ChaCha8Rng::seed_from_u64(cfg.seed);
    let mut run = match &resume {
        None => {
            if let Some(from) = &cfg.init_from {
                let pass_from = cfg.init_pass_from.unwrap_or(naosoccer_proto::Action::Shoot);
                let support_bias = cfg.init_support_bias.unwrap_or(SUPPORT_INIT_BIAS);
                init_weights(&mut ppo, from, pass_from, support_bias)?;
            }
            Run::start(cfg, out, &mut env, &[&ppo.net.vs], true, progress)?
        }
        Some(st) => {
            read_checkpoint(out, st, &mut ppo.net.vs, ppo.adam.as_mut())?;
            ppo.value_norm = st.value_norm;
            rng = st.rng()?;
            Run::resume(cfg, out, st, &mut env, progress)?
        }
    };
    let rows = env.rows();
    let cw = ppo.net.critic_dim;
    let mut dec = Decisions::<Act>::new(&env, decision, scale, cw, cfg.ppo.gamma as f32);
    let mut tr = Transitions::default();
    // Each robot's last transition, while the next one of its stream (the
    // decision that followed) is open.
    let mut link: Vec<Option<usize>> = vec![None; rows];
    let (mut dec_act, mut dec_logp, mut dec_val) = (Vec::new(), Vec::new(), Vec::new());
    let mut acts = Vec::new();
    let (mut cut_rows, mut cut_cobs, mut cut_val) = (Vec::new(), Vec::new(), Vec::new());
    let (mut boot, mut edge_cobs, mut edge_val) = (vec![0.0f32; rows], Vec::new(), vec![0.0; rows]);
    while !run.done() {
        tr.clear();
        let mut ticks = 0usize;
        let mut boundary = false;
        while ticks < cfg.ppo.rollout && !boundary {
            ticks += 1;
            let asked = dec.ask(&env);
            let k = asked.rows.len();
            dec_act.resize(k, 0);
            dec_logp.resize(k, 0.0);
            dec_val.resize(k, 0.0);
            let (obs, ok, banned) = (&asked.obs, &asked.shoot_ok, &asked.banned);
            ppo.act_masked(obs, ok, banned, &mut rng, &mut dec_act, &mut dec_logp);
            ppo.critic_values(&asked.critic_obs, &mut dec_val);
            acts.clear();
            acts.extend(
                dec_logp
                    .iter()
                    .zip(&dec_val)
                    .map(|(&logp, &value)| Act { logp, value }),
            );
            dec.decide(&env, &dec_act, &acts, &mut |c| {
                let End::Decided { next, .. } = c.end else {
                    unreachable!("a decision closes here only by the next one")
                };
                tr.push(&c, dec_val[next], false, &mut link);
            });
            let finished = env.step(dec.actions())?;
            // Episodes cut short (scenarios) are bootstrapped with the
            // critic's value of the state where they were cut.
            dec.cut_critic_rows(&env, &mut cut_rows, &mut cut_cobs);
            cut_val.resize(cut_rows.len(), 0.0);
            ppo.critic_values(&cut_cobs, &mut cut_val);
            for (&r, &v) in cut_rows.iter().zip(&cut_val) {
                boot[r] = v;
            }
            dec.observe(&env, &mut |c| match c.end {
                End::Cut => tr.push(&c, boot[c.row], false, &mut link),
                _ => tr.push(&c, 0.0, true, &mut link),
            });
            run.observe(env.rewards(), finished);
            boundary = env.dones().iter().all(|&d| d);
        }
        // The rollout's edge: open transitions end here, bootstrapped with
        // the critic's value of the state they reached.
        dec.critic_rows(&env, &mut edge_cobs);
        ppo.critic_values(&edge_cobs, &mut edge_val);
        dec.cut(&mut |c| tr.push(&c, edge_val[c.row], false, &mut link));
        let before = run.count(ticks * rows);
        let stats = ppo.update_decisions(&tr, before as f64 / cfg.steps.max(1) as f64, &mut rng);
        run.log(&env, (stats.policy_loss, stats.value_loss, stats.entropy))?;
        run.refresh_opponents(before, &mut env, &[&ppo.net.vs])?;
        if boundary && run.checkpoint_due() {
            let adam = ppo.adam.as_ref();
            run.checkpoint_resumable(&env, &rng, &ppo.net.vs, adam, ppo.value_norm)?;
        }
    }
    run.finish(&[&ppo.net.vs])
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

/// What one update reports.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct UpdateStats {
    pub policy_loss: f64,
    pub value_loss: f64,
    pub entropy: f64,
    /// Mean approximate KL divergence from the rollout's policy (team preset).
    pub approx_kl: f64,
    /// Minibatch steps taken (fewer than epochs x minibatches after a KL stop).
    pub passes: u32,
}

/// The PPO learner: the networks, their optimiser and the value
/// normalisation.
pub struct Ppo {
    pub cfg: PpoConfig,
    pub net: ActorCritic,
    /// The per-tick presets' optimiser ([`crate::ppo_paper`]).
    pub(crate) opt: nn::Optimizer,
    pub(crate) probs: Vec<f32>,
    /// Running statistics of the value targets (`value_norm`).
    pub value_norm: RunningNorm,
    /// The decision-level updates' optimiser (its state is checkpointed,
    /// so a run resumes bit for bit); `None` for the per-tick presets, which
    /// keep tch's Adam.
    pub adam: Option<Adam>,
}

impl Ppo {
    /// The learner for observations of `scale`'s layout and `learners`
    /// robots per team.
    pub fn new(cfg: PpoConfig, scale: &ObsScale, learners: usize) -> Result<Ppo, LearnError> {
        let net = ActorCritic::for_run(&cfg, scale, learners);
        let opt = crate::ppo_paper::optimiser(&cfg, &net.vs)?;
        let adam = cfg.decision.is_some().then(|| {
            Adam::new(&net.vs, vec![cfg.lr_actor, cfg.lr_critic], 1e-5, |name| {
                usize::from(!name.starts_with("actor"))
            })
        });
        Ok(Ppo {
            cfg,
            net,
            opt,
            probs: Vec::new(),
            value_norm: RunningNorm::default(),
            adam,
        })
    }

    /// Samples one action per row (`n` rows of `OBS_DIM`), `shoot` masked
    /// where `shoot_ok` is false and what `banned` bans
    /// ([`naosoccer_policy::actions::banned_actions`]); writes the actions
    /// and their log-probabilities under the masked policy.
    pub fn act_masked(
        &mut self,
        obs: &[f32],
        shoot_ok: &[bool],
        banned: &[ActionSet],
        rng: &mut ChaCha8Rng,
        actions: &mut [usize],
        logp: &mut [f32],
    ) {
        let n = actions.len();
        if n == 0 {
            return;
        }
        let k = self.cfg.actions();
        let x = self.net.actor_input(obs, n);
        let m = action_mask(&shoot_ok[..n], banned, k);
        let mask = Tensor::from_slice(&m).view([n as i64, k as i64]);
        let p = tch::no_grad(|| (self.net.logits(&x) + mask).softmax(-1, Kind::Float));
        self.probs.resize(n * k, 0.0);
        p.copy_data(&mut self.probs, n * k);
        for i in 0..n {
            let row = &self.probs[i * k..(i + 1) * k];
            let a = sample(row, rng.random::<f32>());
            actions[i] = a;
            logp[i] = row[a].max(1e-12).ln();
        }
    }

    /// The critic's values of `n` critic rows (`critic_dim` wide), in
    /// return units (denormalised under `value_norm`).
    pub fn critic_values(&self, rows: &[f32], out: &mut [f32]) {
        let n = out.len();
        if n == 0 {
            return;
        }
        let w = self.net.critic_dim;
        let x = Tensor::from_slice(&rows[..n * w]).view([n as i64, w as i64]);
        tch::no_grad(|| self.net.value(&x)).copy_data(out, n);
        if self.cfg.value_norm {
            for v in out.iter_mut() {
                *v = self.value_norm.denormalise(*v);
            }
        }
    }

    /// One PPO update on decision-level transitions. `progress` in [0, 1]
    /// is how far the run is (learning-rate and entropy schedules).
    pub fn update_decisions(
        &mut self,
        tr: &Transitions,
        progress: f64,
        rng: &mut ChaCha8Rng,
    ) -> UpdateStats {
        let n = tr.len();
        let mut stats = UpdateStats::default();
        if n == 0 {
            return stats;
        }
        let cfg = self.cfg.clone();
        let frac = progress.clamp(0.0, 1.0);
        let Some(mut opt) = self.adam.take() else {
            return stats;
        };
        if let Some(end) = cfg.lr_end_fraction {
            let scale = 1.0 - (1.0 - end) * frac;
            opt.set_lr(0, cfg.lr_actor * scale);
            opt.set_lr(1, cfg.lr_critic * scale);
        }
        let ent_coef = match cfg.entropy_coef_end {
            Some(end) => cfg.entropy_coef + (end - cfg.entropy_coef) * frac,
            None => cfg.entropy_coef,
        };
        let (adv, ret) = tr.gae(cfg.gamma as f32, cfg.gae_lambda as f32);
        let targets: Vec<f32> = if cfg.value_norm {
            self.value_norm.update(&ret);
            ret.iter().map(|&r| self.value_norm.normalise(r)).collect()
        } else {
            ret
        };
        let obs = self.net.actor_input(&tr.obs, n);
        let cw = self.net.critic_dim;
        let cobs = Tensor::from_slice(&tr.critic_obs[..n * cw]).view([n as i64, cw as i64]);
        let actions = Tensor::from_slice(&tr.actions);
        let logp_old = Tensor::from_slice(&tr.logp);
        let k = cfg.actions();
        let mask = Tensor::from_slice(&action_mask(&tr.shoot_ok, &tr.banned, k))
            .view([n as i64, k as i64]);
        let adv = Tensor::from_slice(&adv);
        let targets = Tensor::from_slice(&targets);
        let mb = n.div_ceil(cfg.minibatches.max(1));
        let mut order: Vec<i64> = (0..n as i64).collect();
        let mut count = 0.0;
        'passes: for _ in 0..cfg.epochs {
            shuffle(&mut order, rng);
            for chunk in order.chunks(mb) {
                let idx = Tensor::from_slice(chunk);
                let a = adv.index_select(0, &idx);
                let a = if chunk.len() > 1 {
                    (&a - a.mean(Kind::Float)) / (a.std(true) + 1e-8)
                } else {
                    a
                };
                let logits =
                    self.net.logits(&obs.index_select(0, &idx)) + mask.index_select(0, &idx);
                let logp_all = logits.log_softmax(-1, Kind::Float);
                let logp = logp_all
                    .gather(1, &actions.index_select(0, &idx).unsqueeze(1), false)
                    .squeeze_dim(1);
                let entropy = -(logp_all.exp() * &logp_all)
                    .sum_dim_intlist(-1, false, Kind::Float)
                    .mean(Kind::Float);
                let old = logp_old.index_select(0, &idx);
                let pl = clipped_surrogate_loss(&logp, &old, &a, cfg.clip);
                let v = self.net.value(&cobs.index_select(0, &idx));
                let vl = (&v - targets.index_select(0, &idx))
                    .square()
                    .mean(Kind::Float);
                let loss = &pl + cfg.value_coef * &vl - ent_coef * &entropy;
                opt.zero_grad();
                loss.backward();
                if let Some(m) = cfg.max_grad_norm {
                    opt.clip_grad_norm(m);
                }
                opt.step();
                let kl = tch::no_grad(|| {
                    let lr = logp.detach() - &old;
                    (lr.exp() - 1.0 - &lr).mean(Kind::Float)
                });
                let kl = f64::try_from(&kl).unwrap_or(f64::NAN);
                stats.policy_loss += f64::try_from(&pl).unwrap_or(f64::NAN);
                stats.value_loss += f64::try_from(&vl).unwrap_or(f64::NAN);
                stats.entropy += f64::try_from(&entropy).unwrap_or(f64::NAN);
                stats.approx_kl += kl;
                count += 1.0;
                stats.passes += 1;
                if cfg.target_kl.is_some_and(|t| kl > 1.5 * t) {
                    break 'passes;
                }
            }
        }
        self.adam = Some(opt);
        if count > 0.0 {
            stats.policy_loss /= count;
            stats.value_loss /= count;
            stats.entropy /= count;
            stats.approx_kl /= count;
        }
        stats
    }
}

pub(crate) fn accumulate(total: &mut UpdateStats, s: UpdateStats, count: &mut f64) {
    total.policy_loss += s.policy_loss;
    total.value_loss += s.value_loss;
    total.entropy += s.entropy;
    total.approx_kl += s.approx_kl;
    *count += 1.0;
}

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
        if matches!(c.end, End::Decided { .. }) {
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
}

/// Fisher-Yates with our own RNG, so minibatches repeat with the seed.
pub(crate) fn shuffle(v: &mut [i64], rng: &mut ChaCha8Rng) {
    for i in (1..v.len()).rev() {
        let j = rng.random_range(0..=i);
        v.swap(i, j);
    }
}

#[cfg(test)]
mod tests;
