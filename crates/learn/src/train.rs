//! The training loops, one per algorithm and MDP: they act, store and
//! update, and leave the run directory, metrics, checkpoints, snapshots and
//! opponents to the run harness ([`crate::run`]).

use std::path::Path;

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

use crate::decisions::{critic_row, Decisions, End};
use crate::dqn::{epsilon_greedy, Dqn, NStep};
use crate::env::{Opponent, VecEnv};
use crate::obs::OBS_DIM;
use crate::policy::save_stores;
use crate::ppo::{Act, Ppo, Rollout, Transitions, ACTIONS};
use crate::run::{
    checkpoint_due, make_env, resume_point, set_self_play, snapshot_due, start_schedule,
    write_checkpoint, MetricsRow, Progress, ResumeState, RunDir, Tally, TrainSummary,
};
use crate::schedule_runner::ScheduleRunner;
use crate::warm_start::{init_weights, SUPPORT_INIT_BIAS};
use crate::LearnError;

// The configuration and the self-play snapshot live where the modules that
// read them can reach them without importing the training loops; these are
// their historical paths.
pub use crate::config::{run_scale, Algo, OpponentSpec, TrainConfig};
pub use crate::policy::self_play_snapshot;

/// Trains as `cfg` says, writing the run directory `out`. `progress` sees
/// every metrics row.
pub fn train(
    cfg: &TrainConfig,
    out: &Path,
    progress: &mut dyn FnMut(&Progress<'_>),
) -> Result<TrainSummary, LearnError> {
    tch::manual_seed(cfg.seed as i64);
    match cfg.algo {
        Algo::Ppo => train_ppo(cfg, out, progress),
        Algo::Dqn => train_dqn(cfg, out, progress),
    }
}

/// Continues the run in `dir` from its latest resumable checkpoint, as if
/// it had not stopped (decision-level PPO runs; `steps`, if given, replaces
/// the run's length). metrics.csv keeps the rows up to that checkpoint.
pub fn resume(
    dir: &Path,
    steps: Option<u64>,
    progress: &mut dyn FnMut(&Progress<'_>),
) -> Result<TrainSummary, LearnError> {
    let (cfg, state) = resume_point(dir, steps)?;
    tch::manual_seed(cfg.seed as i64);
    train_ppo_decisions(&cfg, dir, Some(state), progress)
}

fn train_ppo(
    cfg: &TrainConfig,
    out: &Path,
    progress: &mut dyn FnMut(&Progress<'_>),
) -> Result<TrainSummary, LearnError> {
    if cfg.ppo.decision.is_some() {
        return train_ppo_decisions(cfg, out, None, progress);
    }
    let mut env = make_env(cfg)?;
    let mut run = RunDir::create(out, cfg)?;
    let mut ppo = Ppo::new(cfg.ppo.clone(), &run_scale(cfg), cfg.learners.len())?;
    let mut rng = ChaCha8Rng::seed_from_u64(cfg.seed);
    let mut sched = start_schedule(cfg, out, &mut env, &[&ppo.net.vs])?;
    let rows = env.rows();
    let robots = cfg.learners.len();
    let mut tally = Tally::new(robots);
    let mut ro = Rollout::default();
    let (mut actions, mut logp, mut values, mut last_values) = (
        vec![0usize; rows],
        vec![0.0f32; rows],
        vec![0.0f32; rows],
        vec![0.0f32; rows],
    );
    let mut transitions = 0u64;
    let mut update = 0u64;
    let mut out_rows = Vec::new();
    while transitions < cfg.steps {
        ro.clear();
        for _ in 0..cfg.ppo.rollout {
            ro.obs.extend_from_slice(env.observations());
            ppo.act(
                env.observations(),
                &mut rng,
                &mut actions,
                &mut logp,
                &mut values,
            );
            let finished = env.step(&actions)?;
            ro.actions.extend(actions.iter().map(|&a| a as i64));
            ro.logp.extend_from_slice(&logp);
            ro.values.extend_from_slice(&values);
            ro.rewards.extend_from_slice(env.rewards());
            ro.dones
                .extend(env.dones().iter().map(|&d| f32::from(u8::from(d))));
            tally.add_rewards(env.rewards());
            tally.episodes.extend(finished);
        }
        ppo.values(env.observations(), &mut last_values);
        let stats = ppo.update(&ro, rows, &last_values, &mut rng);
        let before = transitions;
        transitions += (cfg.ppo.rollout * rows) as u64;
        update += 1;
        let row = tally.row(
            update,
            env.ticks() / cfg.matches as u64,
            transitions,
            (stats.policy_loss, stats.value_loss, stats.entropy),
        );
        run.write_row(&row)?;
        progress(&Progress {
            row: &row,
            total_steps: cfg.steps,
        });
        out_rows.push(row);
        if checkpoint_due(before, transitions, cfg.checkpoint_every) {
            save_stores(
                &[&ppo.net.vs],
                &out.join(format!("checkpoints/step-{transitions}.safetensors")),
            )?;
        }
        if snapshot_due(cfg, before, transitions) {
            let snap = self_play_snapshot(cfg, Some(&[&ppo.net.vs]))?;
            env.set_opponent(Opponent::Net(Box::new(snap)));
        }
        if let Some(sc) = sched.as_mut() {
            sc.advance(cfg, before, transitions, &mut env, &[&ppo.net.vs])?;
        }
    }
    let final_weights = out.join("final.safetensors");
    save_stores(&[&ppo.net.vs], &final_weights)?;
    Ok(TrainSummary {
        rows: out_rows,
        transitions,
        final_weights,
    })
}

/// The decision-level PPO loop (`team` preset): every tick each learning
/// robot either decides (free to act, persistence run out: a forward pass,
/// its open transition closes with the new decision's value) or holds its
/// action; rewards accumulate into the open transition discounted per tick;
/// an episode's end closes it with no bootstrap, the rollout's edge with the
/// critic's value of the edge state.
fn train_ppo_decisions(
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
    let l = cfg.learners.len();
    let mut ppo = Ppo::new(cfg.ppo.clone(), &scale, l)?;
    let mut rng = ChaCha8Rng::seed_from_u64(cfg.seed);
    let mut tally = Tally::new(l);
    let mut transitions = 0u64;
    let mut update = 0u64;
    // The self-play snapshot in play (weights file under pool/).
    let mut self_play: Option<String> = None;
    let (mut run, mut sched) = match &resume {
        None => {
            if let Some(from) = &cfg.init_from {
                let pass_from = cfg.init_pass_from.unwrap_or(naosoccer_proto::Action::Shoot);
                let support_bias = cfg.init_support_bias.unwrap_or(SUPPORT_INIT_BIAS);
                init_weights(&mut ppo, from, pass_from, support_bias)?;
            }
            let run = RunDir::create(out, cfg)?;
            let sched = start_schedule(cfg, out, &mut env, &[&ppo.net.vs])?;
            if matches!(cfg.opponent, OpponentSpec::SelfPlay { .. }) {
                let name = "self-play-step-0.safetensors".to_string();
                set_self_play(cfg, out, &name, Some(&ppo.net.vs), &mut env)?;
                self_play = Some(name);
            }
            (run, sched)
        }
        Some(st) => {
            let ck = out.join("checkpoints");
            ppo.net
                .vs
                .load(ck.join(format!("step-{}.safetensors", st.transitions)))?;
            let named = tch::Tensor::read_safetensors(
                ck.join(format!("step-{}.adam.safetensors", st.transitions)),
            )?;
            if let Some(a) = ppo.adam.as_mut() {
                a.load_state(&named)?;
            }
            ppo.value_norm = st.value_norm;
            rng = st.rng()?;
            transitions = st.transitions;
            update = st.update;
            tally.total_episodes = st.total_episodes;
            env.restart_at(&st.episodes, st.env_ticks)?;
            let sched = match (&cfg.opponent, &st.schedule) {
                (OpponentSpec::Schedule(s), Some(state)) => {
                    Some(ScheduleRunner::resume(s, cfg, out, &mut env, state)?)
                }
                _ => None,
            };
            if let Some(name) = &st.self_play {
                set_self_play(cfg, out, name, None, &mut env)?;
                self_play = Some(name.clone());
            }
            (RunDir::reopen(out, st.update)?, sched)
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
    let mut boot = vec![0.0f32; rows];
    let mut out_rows = Vec::new();
    let mut last_checkpoint = transitions;
    while transitions < cfg.steps {
        tr.clear();
        let mut ticks = 0usize;
        // A rollout also ends with the episodes (all matches have one
        // length and end together): checkpoints fall on episode
        // boundaries, where a resumed run can rebuild the matches exactly.
        let mut boundary = false;
        while ticks < cfg.ppo.rollout && !boundary {
            ticks += 1;
            let asked = dec.ask(&env);
            let k = asked.rows.len();
            dec_act.resize(k, 0);
            dec_logp.resize(k, 0.0);
            dec_val.resize(k, 0.0);
            ppo.act_masked(
                &asked.obs,
                &asked.shoot_ok,
                &asked.banned,
                &mut rng,
                &mut dec_act,
                &mut dec_logp,
            );
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
            // Episodes cut short (pass drills) are bootstrapped with the
            // critic's value of the state where they were cut.
            cut_rows.clear();
            cut_cobs.clear();
            for r in 0..rows {
                if env.truncated()[r] {
                    cut_rows.push(r);
                    critic_row(
                        env.final_observations(),
                        l,
                        r,
                        scale.dim(),
                        cw,
                        &mut cut_cobs,
                    );
                }
            }
            cut_val.resize(cut_rows.len(), 0.0);
            if !cut_rows.is_empty() {
                ppo.critic_values(&cut_cobs, &mut cut_val);
            }
            for (&r, &v) in cut_rows.iter().zip(&cut_val) {
                boot[r] = v;
            }
            dec.observe(&env, &mut |c| match c.end {
                End::Cut => tr.push(&c, boot[c.row], false, &mut link),
                _ => tr.push(&c, 0.0, true, &mut link),
            });
            tally.add_rewards(env.rewards());
            tally.episodes.extend(finished);
            boundary = env.dones().iter().all(|&d| d);
        }
        // The rollout's edge: open transitions end here, bootstrapped with
        // the critic's value of the state they reached.
        let mut edge_cobs = Vec::with_capacity(rows * cw);
        for r in 0..rows {
            critic_row(env.observations(), l, r, scale.dim(), cw, &mut edge_cobs);
        }
        let mut edge_val = vec![0.0f32; rows];
        ppo.critic_values(&edge_cobs, &mut edge_val);
        dec.cut(&mut |c| tr.push(&c, edge_val[c.row], false, &mut link));
        let before = transitions;
        transitions += (ticks * rows) as u64;
        let stats = ppo.update_decisions(&tr, before as f64 / cfg.steps.max(1) as f64, &mut rng);
        update += 1;
        let row = tally.row(
            update,
            env.ticks() / cfg.matches as u64,
            transitions,
            (stats.policy_loss, stats.value_loss, stats.entropy),
        );
        run.write_row(&row)?;
        progress(&Progress {
            row: &row,
            total_steps: cfg.steps,
        });
        out_rows.push(row);
        if snapshot_due(cfg, before, transitions) {
            let name = format!("self-play-step-{transitions}.safetensors");
            set_self_play(cfg, out, &name, Some(&ppo.net.vs), &mut env)?;
            self_play = Some(name);
        }
        if let Some(sc) = sched.as_mut() {
            sc.advance(cfg, before, transitions, &mut env, &[&ppo.net.vs])?;
        }
        if boundary && checkpoint_due(last_checkpoint, transitions, cfg.checkpoint_every) {
            last_checkpoint = transitions;
            let state = ResumeState {
                transitions,
                update,
                env_ticks: env.ticks(),
                episodes: env.episodes(),
                total_episodes: tally.total_episodes,
                rng_seed: rng.get_seed(),
                rng_stream: rng.get_stream(),
                rng_word_pos: rng.get_word_pos().to_string(),
                value_norm: ppo.value_norm,
                schedule: sched.as_ref().map(ScheduleRunner::state),
                self_play: self_play.clone(),
            };
            write_checkpoint(out, &ppo.net.vs, ppo.adam.as_ref(), &state)?;
        }
    }
    let final_weights = out.join("final.safetensors");
    save_stores(&[&ppo.net.vs], &final_weights)?;
    Ok(TrainSummary {
        rows: out_rows,
        transitions,
        final_weights,
    })
}

/// What both DQN loops keep between vectorised steps: the counters, the
/// loss since the last metrics row and the rows written.
#[derive(Default)]
struct DqnLog {
    transitions: u64,
    update: u64,
    step: usize,
    loss_sum: f64,
    loss_n: u32,
    rows: Vec<MetricsRow>,
}

impl DqnLog {
    fn add_loss(&mut self, loss: Option<f64>) {
        if let Some(l) = loss {
            self.loss_sum += l;
            self.loss_n += 1;
        }
    }

    /// After a vectorised step of `rows` transitions: a metrics row every
    /// `log_every` steps (and at the end), checkpoints and self-play
    /// snapshots when they fall due.
    #[allow(clippy::too_many_arguments)]
    fn end_step(
        &mut self,
        cfg: &TrainConfig,
        out: &Path,
        rows: usize,
        env: &mut VecEnv,
        tally: &mut Tally,
        run: &mut RunDir,
        progress: &mut dyn FnMut(&Progress<'_>),
        dqn: &Dqn,
    ) -> Result<(), LearnError> {
        let before = self.transitions;
        self.transitions += rows as u64;
        self.step += 1;
        if self.step.is_multiple_of(cfg.log_every.max(1)) || self.transitions >= cfg.steps {
            self.update += 1;
            let loss = if self.loss_n > 0 {
                self.loss_sum / f64::from(self.loss_n)
            } else {
                f64::NAN
            };
            let row = tally.row(
                self.update,
                env.ticks() / cfg.matches as u64,
                self.transitions,
                (loss, f64::NAN, f64::NAN),
            );
            self.loss_sum = 0.0;
            self.loss_n = 0;
            run.write_row(&row)?;
            progress(&Progress {
                row: &row,
                total_steps: cfg.steps,
            });
            self.rows.push(row);
        }
        let stores: Vec<&tch::nn::VarStore> = dqn.nets.iter().map(|n| &n.vs).collect();
        if checkpoint_due(before, self.transitions, cfg.checkpoint_every) {
            let name = format!("checkpoints/step-{}.safetensors", self.transitions);
            save_stores(&stores, &out.join(name))?;
        }
        if snapshot_due(cfg, before, self.transitions) {
            let snap = self_play_snapshot(cfg, Some(&stores))?;
            env.set_opponent(Opponent::Net(Box::new(snap)));
        }
        Ok(())
    }

    /// Saves the final weights and sums the run up.
    fn finish(self, out: &Path, dqn: &Dqn) -> Result<TrainSummary, LearnError> {
        let final_weights = out.join("final.safetensors");
        let stores: Vec<&tch::nn::VarStore> = dqn.nets.iter().map(|n| &n.vs).collect();
        save_stores(&stores, &final_weights)?;
        Ok(TrainSummary {
            rows: self.rows,
            transitions: self.transitions,
            final_weights,
        })
    }
}

/// DQN on the decision-level MDP: each tick, the robots free to act whose
/// last decision ran out decide (epsilon-greedy over the actions allowed
/// them); a decision closes when the robot next decides, or when the
/// episode ends, and enters the n-step accumulator as one transition with
/// its discounted reward and discount `gamma^ticks`.
fn train_dqn_decisions(
    cfg: &TrainConfig,
    out: &Path,
    progress: &mut dyn FnMut(&Progress<'_>),
) -> Result<TrainSummary, LearnError> {
    let decision = cfg
        .dqn
        .decision
        .ok_or_else(|| LearnError::Config("no decision configuration".into()))?;
    let mut env = make_env(cfg)?;
    let mut run = RunDir::create(out, cfg)?;
    let scale = run_scale(cfg);
    let robots = cfg.learners.len();
    let mut dqn = Dqn::new(cfg.dqn.clone(), robots, run_scale(cfg).dim())?;
    let mut rng = ChaCha8Rng::seed_from_u64(cfg.seed);
    let rows = env.rows();
    let mut tally = Tally::new(robots);
    let mut dec = Decisions::<()>::new(&env, decision, scale, 0, cfg.dqn.discount(1));
    let mut q = Vec::new();
    let mut chosen = Vec::new();
    let mut nstep = NStep::new(cfg.dqn.n_step, rows);
    let mut log = DqnLog::default();
    while log.transitions < cfg.steps {
        let asked = dec.ask(&env);
        let any = !asked.rows.is_empty();
        if any {
            let obs = env.observations();
            dqn.q_values(obs, robots, &mut q);
            let epsilon = cfg.dqn.epsilon_at(log.transitions);
            chosen.clear();
            for (&r, &ok) in asked.rows.iter().zip(&asked.shoot_ok) {
                let q = &q[r * ACTIONS..(r + 1) * ACTIONS];
                chosen.push(epsilon_greedy(q, ok, epsilon, &mut rng));
            }
            let none = vec![(); chosen.len()];
            dec.decide(&env, &chosen, &none, &mut |c| {
                // The decision that ran until now ends in this state.
                let End::Decided { shoot_ok, .. } = c.end else {
                    unreachable!("a decision closes here only by the next one")
                };
                let (r, next) = (c.row, &obs[c.row * OBS_DIM..(c.row + 1) * OBS_DIM]);
                nstep.push(r, c.obs, c.action, c.reward, c.discount, false, &mut |t| {
                    dqn.remember(
                        r % robots,
                        t.obs,
                        t.action,
                        t.ret,
                        next,
                        t.discount,
                        shoot_ok,
                    )
                });
            });
        }
        let finished = env.step(dec.actions())?;
        dec.observe(&env, &mut |c| {
            // Terminal: the next observation is never bootstrapped from.
            let r = c.row;
            nstep.push(r, c.obs, c.action, c.reward, c.discount, true, &mut |t| {
                dqn.remember(r % robots, t.obs, t.action, t.ret, c.obs, t.discount, true)
            });
        });
        tally.add_rewards(env.rewards());
        tally.episodes.extend(finished);
        if any {
            log.add_loss(dqn.learn(&mut rng));
        }
        log.end_step(
            cfg, out, rows, &mut env, &mut tally, &mut run, progress, &dqn,
        )?;
    }
    log.finish(out, &dqn)
}

fn train_dqn(
    cfg: &TrainConfig,
    out: &Path,
    progress: &mut dyn FnMut(&Progress<'_>),
) -> Result<TrainSummary, LearnError> {
    if cfg.dqn.decision.is_some() {
        return train_dqn_decisions(cfg, out, progress);
    }
    let mut env = make_env(cfg)?;
    let mut run = RunDir::create(out, cfg)?;
    let robots = cfg.learners.len();
    let mut dqn = Dqn::new(cfg.dqn.clone(), robots, run_scale(cfg).dim())?;
    let mut rng = ChaCha8Rng::seed_from_u64(cfg.seed);
    let rows = env.rows();
    let mut tally = Tally::new(robots);
    let mut actions = vec![0usize; rows];
    let mut prev = vec![0.0f32; rows * OBS_DIM];
    let mut log = DqnLog::default();
    let mut nstep = NStep::new(cfg.dqn.n_step, rows);
    // Every transition here lasts one control tick.
    let discount = cfg.dqn.discount(1);
    while log.transitions < cfg.steps {
        prev.copy_from_slice(env.observations());
        let epsilon = cfg.dqn.epsilon_at(log.transitions);
        dqn.act(&prev, robots, epsilon, &mut rng, &mut actions);
        let finished = env.step(&actions)?;
        let next = env.observations();
        for i in 0..rows {
            let next_obs = &next[i * OBS_DIM..(i + 1) * OBS_DIM];
            nstep.push(
                i,
                &prev[i * OBS_DIM..(i + 1) * OBS_DIM],
                actions[i],
                env.rewards()[i],
                discount,
                env.dones()[i],
                &mut |t| {
                    dqn.remember(
                        i % robots,
                        t.obs,
                        t.action,
                        t.ret,
                        next_obs,
                        t.discount,
                        true,
                    )
                },
            );
        }
        tally.add_rewards(env.rewards());
        tally.episodes.extend(finished);
        log.add_loss(dqn.learn(&mut rng));
        log.end_step(
            cfg, out, rows, &mut env, &mut tally, &mut run, progress, &dqn,
        )?;
    }
    log.finish(out, &dqn)
}
