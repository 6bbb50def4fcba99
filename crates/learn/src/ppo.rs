//! PPO for a team, in three presets over one loop: the decision-level
//! MDP ([`crate::env::decisions`]), in which robots decide every tick in
//! the per-tick presets and only when free to act in `team`.
//!
//! - `team`: a robot decides only when it is free to act, movement
//!   persists, `shoot` (and what [`DecisionConfig`] bans) is masked, and a
//!   transition spans the ticks from one decision to the next: returns are
//!   discounted by the time that elapsed (`gamma^dt`, GAE with
//!   `(gamma lambda)^dt`), bootstrapped at rollout edges and where a drill
//!   cut an episode. On top of CleanRL's machinery: value normalisation, a
//!   KL early stop, learning-rate and entropy schedules, an optional
//!   centralised critic (MAPPO: the critic reads the whole team's
//!   observation vectors), and an optimiser whose state a checkpoint saves.
//! - `cleanrl`: CleanRL's `ppo.py`: every robot decides every tick; GAE
//!   bootstrapped at the rollout's end, shuffled minibatches, gradient-norm
//!   clipping.
//! - `paper`: the paper's Algorithm 2: every robot decides every tick;
//!   discounted returns normalised over the batch, `A = R_norm - V(s)`,
//!   `K` epochs over the whole batch.
//!
//! Read top to bottom: the loop ([`train`]), acting ([`Ppo::act_masked`],
//! [`Ppo::critic_values`]) and the update ([`Ppo::update`]). What it
//! stores and its estimators are [`crate::rollout`]'s; the run directory,
//! metrics, opponents and checkpoints are the harness's ([`crate::run`]).

use std::path::Path;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use tch::nn::{self, OptimizerConfig};
use tch::{Kind, Tensor};

use crate::adam::Adam;
use crate::config::{run_scale, PpoConfig, Preset, TrainConfig};
use crate::env::decisions::{Decisions, End};
use crate::metrics::Progress;
use crate::nets::{self, ActorCritic, RunningNorm};
use crate::obs::ObsScale;
pub use crate::rollout::{Act, Transitions};
use crate::run::resume::{read_checkpoint, ResumeState};
use crate::run::{make_env, Run, TrainSummary};
use crate::warm_start::{init_weights, SUPPORT_INIT_BIAS};
use crate::LearnError;
use naosoccer_policy::actions::ActionSet;

pub use naosoccer_policy::actions::{
    action_count, action_mask, sample, shoot_mask, DecisionConfig, NetAction, ACTIONS,
};

/// Trains a PPO run into `out`, or goes on from `resume` (a checkpoint of
/// a `team` run in `out`) as if it had not stopped.
///
/// Every tick each learning robot either decides (a forward pass; its open
/// transition closes with the new decision's value) or holds its action;
/// an episode's end closes it with no bootstrap, a drill's cut and the
/// rollout's edge with the critic's value of the state reached. In the
/// per-tick presets (`paper`, `cleanrl`: no decision settings) every robot
/// decides every tick and each decision closes at the tick's end, with the
/// value of the state reached. A `team` rollout also ends with the
/// episodes (all matches have one length and end together): its
/// checkpoints fall on episode boundaries, where a resumed run can rebuild
/// the matches exactly.
pub fn train(
    cfg: &TrainConfig,
    out: &Path,
    resume: Option<ResumeState>,
    progress: &mut dyn FnMut(&Progress<'_>),
) -> Result<TrainSummary, LearnError> {
    let decision = cfg.ppo.decision;
    let per_tick = decision.is_none();
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
            Run::start(cfg, out, &mut env, &[&ppo.net.vs], !per_tick, progress)?
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
    let (mut acts, mut asked_rows) = (Vec::new(), Vec::new());
    // Transitions closed by a decision, waiting for its value: (the
    // transition, the decision's index this tick).
    let mut waiting: Vec<(usize, usize)> = Vec::new();
    let (mut cut_rows, mut cut_cobs, mut cut_val) = (Vec::new(), Vec::new(), Vec::new());
    let (mut boot, mut now_cobs, mut now_val) = (vec![0.0f32; rows], Vec::new(), vec![0.0; rows]);
    while !run.done() {
        // A rollout's streams start afresh: its last transitions were cut
        // by its edge, or (per tick) ended with its last tick.
        tr.clear();
        link.fill(None);
        let mut ticks = 0usize;
        let mut boundary = false;
        // A `team` rollout also ends with the episodes.
        while ticks < cfg.ppo.rollout && (per_tick || !boundary) {
            ticks += 1;
            let asked = dec.ask(&env);
            let k = asked.rows.len();
            dec_act.resize(k, 0);
            dec_logp.resize(k, 0.0);
            dec_val.resize(k, 0.0);
            let (obs, ok, banned) = (&asked.obs, &asked.shoot_ok, &asked.banned);
            ppo.act_masked(obs, ok, banned, &mut rng, &mut dec_act, &mut dec_logp);
            asked_rows.clone_from(&asked.rows);
            // The critic's values of the decisions are filled in below,
            // computed while the matches step: the tick needs only the
            // actions.
            acts.clear();
            acts.extend(dec_logp.iter().map(|&logp| Act { logp, value: 0.0 }));
            waiting.clear();
            dec.decide(&env, &dec_act, &acts, &mut |c| {
                let End::Decided { next, .. } = c.end else {
                    unreachable!("a decision closes here only by the next one")
                };
                waiting.push((tr.len(), next));
                tr.push(&c, 0.0, false, &mut link);
            });
            let critic_obs = &dec.asked().critic_obs;
            let finished = env.step_beside(dec.actions(), || {
                ppo.critic_values(critic_obs, &mut dec_val);
            })?;
            for &(i, next) in &waiting {
                tr.next_values[i] = dec_val[next];
            }
            for (&r, &value) in asked_rows.iter().zip(&dec_val) {
                if let Some(p) = dec.payload_mut(r) {
                    p.value = value;
                }
            }
            // Episodes cut short (scenarios) are bootstrapped with the
            // critic's value of the state where they were cut.
            dec.cut_critic_rows(&env, &mut cut_rows, &mut cut_cobs);
            cut_val.resize(cut_rows.len(), 0.0);
            ppo.critic_values(&cut_cobs, &mut cut_val);
            for (&r, &v) in cut_rows.iter().zip(&cut_val) {
                boot[r] = v;
            }
            if per_tick {
                // Decisions of one tick end in the state reached.
                dec.critic_rows(&env, &mut now_cobs);
                ppo.critic_values(&now_cobs, &mut now_val);
            }
            dec.observe(&env, &mut |c| match c.end {
                End::Cut => tr.push(&c, boot[c.row], false, &mut link),
                End::Tick => tr.push(&c, now_val[c.row], false, &mut link),
                _ => tr.push(&c, 0.0, true, &mut link),
            });
            run.observe(env.rewards(), finished);
            boundary = env.dones().iter().all(|&d| d);
        }
        // The rollout's edge: open transitions end here, bootstrapped with
        // the critic's value of the state they reached (none are open in
        // the per-tick presets).
        if !per_tick {
            dec.critic_rows(&env, &mut now_cobs);
            ppo.critic_values(&now_cobs, &mut now_val);
            dec.cut(&mut |c| tr.push(&c, now_val[c.row], false, &mut link));
        }
        let before = run.count(ticks * rows);
        let stats = ppo.update(&tr, before as f64 / cfg.steps.max(1) as f64, &mut rng);
        run.log(&env, (stats.policy_loss, stats.value_loss, stats.entropy))?;
        run.refresh_opponents(before, &mut env, &[&ppo.net.vs])?;
        if per_tick && run.checkpoint_due() {
            run.checkpoint(&[&ppo.net.vs])?;
        } else if boundary && run.checkpoint_due() {
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
    /// The per-tick presets' optimiser.
    opt: nn::Optimizer,
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
        let opt = optimiser(&cfg, &net.vs)?;
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

    /// One PPO update on the rollout's transitions. `progress` in [0, 1]
    /// is how far the run is (learning-rate and entropy schedules).
    ///
    /// The targets and advantages are GAE's (`team`, `cleanrl`) or, in the
    /// paper's Algorithm 2 (`paper`), the discounted returns normalised over
    /// the batch, with `A = R_norm - V(s)` taken afresh at every step. The
    /// paper steps once over the whole batch per epoch; the others over
    /// shuffled minibatches, each normalising its advantages.
    pub fn update(&mut self, tr: &Transitions, progress: f64, rng: &mut ChaCha8Rng) -> UpdateStats {
        let n = tr.len();
        let mut stats = UpdateStats::default();
        if n == 0 {
            return stats;
        }
        let cfg = self.cfg.clone();
        let frac = progress.clamp(0.0, 1.0);
        if let (Some(end), Some(opt)) = (cfg.lr_end_fraction, self.adam.as_mut()) {
            let scale = 1.0 - (1.0 - end) * frac;
            opt.set_lr(0, cfg.lr_actor * scale);
            opt.set_lr(1, cfg.lr_critic * scale);
        }
        let ent_coef = match cfg.entropy_coef_end {
            Some(end) => cfg.entropy_coef + (end - cfg.entropy_coef) * frac,
            None => cfg.entropy_coef,
        };
        let paper = cfg.preset == Preset::Paper;
        let (adv, targets) = if paper {
            let r = Tensor::from_slice(&tr.discounted_returns(cfg.gamma as f32));
            (None, (&r - r.mean(Kind::Float)) / (r.std(true) + 1e-7))
        } else {
            let (adv, ret) = tr.gae(cfg.gamma as f32, cfg.gae_lambda as f32);
            let targets: Vec<f32> = if cfg.value_norm {
                self.value_norm.update(&ret);
                ret.iter().map(|&r| self.value_norm.normalise(r)).collect()
            } else {
                ret
            };
            (Some(Tensor::from_slice(&adv)), Tensor::from_slice(&targets))
        };
        let obs = self.net.actor_input(&tr.obs, n);
        let cw = self.net.critic_dim;
        let cobs = Tensor::from_slice(&tr.critic_obs[..n * cw]).view([n as i64, cw as i64]);
        let actions = Tensor::from_slice(&tr.actions);
        let logp_old = Tensor::from_slice(&tr.logp);
        let k = cfg.actions();
        let mask = Tensor::from_slice(&action_mask(&tr.shoot_ok, &tr.banned, k))
            .view([n as i64, k as i64]);
        let mb = if paper {
            n
        } else {
            n.div_ceil(cfg.minibatches.max(1))
        };
        let mut order: Vec<i64> = (0..n as i64).collect();
        let mut count = 0.0;
        // The critic's thread computes with as many threads as this one.
        let torch_threads = tch::get_num_threads();
        // The team's optimiser is ours (a checkpoint saves its state); the
        // per-tick presets keep tch's.
        let opt: &mut dyn Optimiser = match self.adam.as_mut() {
            Some(adam) => adam,
            None => &mut self.opt,
        };
        'passes: for _ in 0..cfg.epochs {
            if !paper {
                shuffle(&mut order, rng);
            }
            for chunk in order.chunks(mb) {
                let idx = Tensor::from_slice(chunk);
                opt.zero_grad();
                let (actor, critic) = self.net.parts();
                let logits = actor.forward(&obs.index_select(0, &idx)) + mask.index_select(0, &idx);
                let logp_all = logits.log_softmax(-1, Kind::Float);
                let logp = logp_all
                    .gather(1, &actions.index_select(0, &idx).unsqueeze(1), false)
                    .squeeze_dim(1);
                let entropy = -(logp_all.exp() * &logp_all)
                    .sum_dim_intlist(-1, false, Kind::Float)
                    .mean(Kind::Float);
                let old = logp_old.index_select(0, &idx);
                let (pl, vl) = match &adv {
                    // GAE's advantages do not take the critic: its loss is
                    // back-propagated on a second thread while this one
                    // does the actor's. The two share no variable and each
                    // gets the gradients the sum's backward pass gives it
                    // (the same operations, so the same bits), in about
                    // half the time.
                    Some(adv) => {
                        let (cobs, targets) = (cobs.shallow_clone(), targets.shallow_clone());
                        let critic_idx = idx.shallow_clone();
                        std::thread::scope(|s| {
                            let critic_loss = s.spawn(move || {
                                tch::set_num_threads(torch_threads);
                                let idx = critic_idx;
                                let v = nets::value(critic, &cobs.index_select(0, &idx));
                                let vl = (&v - targets.index_select(0, &idx))
                                    .square()
                                    .mean(Kind::Float);
                                (cfg.value_coef * &vl).backward();
                                vl
                            });
                            let a = adv.index_select(0, &idx);
                            let a = if chunk.len() > 1 {
                                (&a - a.mean(Kind::Float)) / (a.std(true) + 1e-8)
                            } else {
                                a
                            };
                            let pl = clipped_surrogate_loss(&logp, &old, &a, cfg.clip);
                            (&pl - ent_coef * &entropy).backward();
                            let vl = critic_loss
                                .join()
                                .unwrap_or_else(|e| std::panic::resume_unwind(e));
                            (pl, vl)
                        })
                    }
                    // The paper's advantages take the critic's values.
                    None => {
                        let target = targets.index_select(0, &idx);
                        let v = nets::value(critic, &cobs.index_select(0, &idx));
                        let a = &target - v.detach();
                        let pl = clipped_surrogate_loss(&logp, &old, &a, cfg.clip);
                        let vl = (&v - &target).square().mean(Kind::Float);
                        (&pl + cfg.value_coef * &vl - ent_coef * &entropy).backward();
                        (pl, vl)
                    }
                };
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
        if count > 0.0 {
            stats.policy_loss /= count;
            stats.value_loss /= count;
            stats.entropy /= count;
            stats.approx_kl /= count;
        }
        stats
    }
}

/// What an update needs of an optimiser: ours ([`Adam`], the `team`
/// preset's) or tch's (the per-tick presets').
trait Optimiser {
    fn zero_grad(&mut self);
    fn clip_grad_norm(&mut self, max: f64);
    fn step(&mut self);
}

impl Optimiser for Adam {
    fn zero_grad(&mut self) {
        Adam::zero_grad(self);
    }
    fn clip_grad_norm(&mut self, max: f64) {
        Adam::clip_grad_norm(self, max);
    }
    fn step(&mut self) {
        Adam::step(self);
    }
}

impl Optimiser for nn::Optimizer {
    fn zero_grad(&mut self) {
        nn::Optimizer::zero_grad(self);
    }
    fn clip_grad_norm(&mut self, max: f64) {
        nn::Optimizer::clip_grad_norm(self, max);
    }
    fn step(&mut self) {
        nn::Optimizer::step(self);
    }
}

/// The per-tick presets' optimiser: tch's Adam with the actor's and the
/// critic's learning rates (and CleanRL's epsilon for `cleanrl`).
fn optimiser(cfg: &PpoConfig, vs: &nn::VarStore) -> Result<nn::Optimizer, LearnError> {
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

/// Fisher-Yates with our own RNG, so minibatches repeat with the seed.
pub(crate) fn shuffle(v: &mut [i64], rng: &mut ChaCha8Rng) {
    for i in (1..v.len()).rev() {
        let j = rng.random_range(0..=i);
        v.swap(i, j);
    }
}

#[cfg(test)]
mod tests;
