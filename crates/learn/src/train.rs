//! Training runs: the configuration saved beside the checkpoints, the loop
//! for each algorithm, and the metrics CSV.
//!
//! A run directory:
//! - `config.json`: this [`TrainConfig`] (networks, hyperparameters, match
//!   configuration, observation layout version and scale),
//! - `metrics.csv`: one row per update (PPO) or log interval (DQN),
//! - `checkpoints/step-N.safetensors` every `checkpoint_every` transitions,
//! - `final.safetensors` at the end.
//!
//! Nothing here reads the clock: the same configuration, seed and thread
//! count write the same metrics.

use std::io::Write;
use std::path::{Path, PathBuf};

use naosoccer_client::PolicyKind;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

use crate::dqn::{epsilon_greedy, Dqn, NStep};
use crate::env::{EnvConfig, Episode, Opponent, VecEnv};
use crate::obs::{layout_dim, OBS_DIM, OBS_VERSION_LATEST};
use crate::policy::{save_stores, Hold, LearnedPolicy};
use crate::ppo::{Ppo, Rollout, Transitions, ACTIONS};
use crate::schedule_runner::ScheduleRunner;
use crate::LearnError;
use naosoccer_policy::actions::banned_actions;

// The configuration and the self-play snapshot live where the modules that
// read them can reach them without importing the training loops; these are
// their historical paths.
pub use crate::config::{run_scale, Algo, OpponentSpec, TrainConfig};
pub use crate::policy::self_play_snapshot;

/// One row of `metrics.csv`.
#[derive(Debug, Clone, PartialEq)]
pub struct MetricsRow {
    pub update: u64,
    /// Control ticks per match so far (the figures' "timeslots").
    pub timeslot: u64,
    pub transitions: u64,
    pub episodes: u64,
    /// Mean reward per robot and tick over this row's interval, for the team
    /// and per learning robot.
    pub reward: f64,
    pub reward_per_robot: Vec<f64>,
    /// Mean over episodes that ended in this interval (NaN when none did).
    pub episode_return: f64,
    pub goals_for: f64,
    pub goals_against: f64,
    /// PPO: policy loss; DQN: TD loss.
    pub loss: f64,
    pub value_loss: f64,
    pub entropy: f64,
}

impl MetricsRow {
    pub fn header(robots: &[usize]) -> String {
        let mut h = String::from("update,timeslot,transitions,episodes,reward");
        for p in robots {
            h.push_str(&format!(",reward_p{p}"));
        }
        h.push_str(",episode_return,goals_for,goals_against,loss,value_loss,entropy");
        h
    }

    pub fn to_csv(&self) -> String {
        let mut s = format!(
            "{},{},{},{},{:.6}",
            self.update, self.timeslot, self.transitions, self.episodes, self.reward
        );
        for r in &self.reward_per_robot {
            s.push_str(&format!(",{r:.6}"));
        }
        s.push_str(&format!(
            ",{:.6},{:.4},{:.4},{:.6},{:.6},{:.6}",
            self.episode_return,
            self.goals_for,
            self.goals_against,
            self.loss,
            self.value_loss,
            self.entropy
        ));
        s
    }
}

/// What a run reports as it goes (the CLI adds wall-clock rates).
#[derive(Debug, Clone)]
pub struct Progress<'a> {
    pub row: &'a MetricsRow,
    pub total_steps: u64,
}

/// Accumulates rewards and finished episodes between metric rows.
struct Tally {
    robots: usize,
    reward_sum: Vec<f64>,
    samples: u64,
    episodes: Vec<Episode>,
    total_episodes: u64,
}

impl Tally {
    fn new(robots: usize) -> Tally {
        Tally {
            robots,
            reward_sum: vec![0.0; robots],
            samples: 0,
            episodes: Vec::new(),
            total_episodes: 0,
        }
    }

    fn add_rewards(&mut self, rewards: &[f32]) {
        for (i, r) in rewards.iter().enumerate() {
            self.reward_sum[i % self.robots] += f64::from(*r);
        }
        self.samples += (rewards.len() / self.robots) as u64;
    }

    fn row(
        &mut self,
        update: u64,
        timeslot: u64,
        transitions: u64,
        losses: (f64, f64, f64),
    ) -> MetricsRow {
        let per: Vec<f64> = self
            .reward_sum
            .iter()
            .map(|s| s / self.samples.max(1) as f64)
            .collect();
        let reward = per.iter().sum::<f64>() / per.len() as f64;
        let n = self.episodes.len();
        let mean = |f: &dyn Fn(&Episode) -> f64| {
            if n == 0 {
                f64::NAN
            } else {
                self.episodes.iter().map(f).sum::<f64>() / n as f64
            }
        };
        let episode_return = mean(&|e| {
            e.returns.iter().map(|&r| f64::from(r)).sum::<f64>() / e.returns.len() as f64
        });
        let goals_for = mean(&|e| f64::from(e.goals_for));
        let goals_against = mean(&|e| f64::from(e.goals_against));
        self.total_episodes += n as u64;
        let row = MetricsRow {
            update,
            timeslot,
            transitions,
            episodes: self.total_episodes,
            reward,
            reward_per_robot: per,
            episode_return,
            goals_for,
            goals_against,
            loss: losses.0,
            value_loss: losses.1,
            entropy: losses.2,
        };
        self.reward_sum.iter_mut().for_each(|s| *s = 0.0);
        self.samples = 0;
        self.episodes.clear();
        row
    }
}

/// Writes the run directory as training goes.
struct RunDir {
    dir: PathBuf,
    metrics: std::io::BufWriter<std::fs::File>,
}

impl RunDir {
    fn create(dir: &Path, cfg: &TrainConfig) -> Result<RunDir, LearnError> {
        std::fs::create_dir_all(dir.join("checkpoints")).map_err(|e| LearnError::io(dir, e))?;
        let cfg_path = dir.join("config.json");
        let json = serde_json::to_string_pretty(cfg).map_err(|e| LearnError::json(&cfg_path, e))?;
        std::fs::write(&cfg_path, json).map_err(|e| LearnError::io(&cfg_path, e))?;
        let mpath = dir.join("metrics.csv");
        let f = std::fs::File::create(&mpath).map_err(|e| LearnError::io(&mpath, e))?;
        let mut metrics = std::io::BufWriter::new(f);
        writeln!(metrics, "{}", MetricsRow::header(&cfg.learners))
            .map_err(|e| LearnError::io(&mpath, e))?;
        Ok(RunDir {
            dir: dir.to_path_buf(),
            metrics,
        })
    }

    /// Reopens a run directory to go on from a checkpoint: metrics.csv keeps
    /// its header and its first `rows` rows (those written up to the
    /// checkpoint) and grows from there.
    fn reopen(dir: &Path, rows: u64) -> Result<RunDir, LearnError> {
        let mpath = dir.join("metrics.csv");
        let text = std::fs::read_to_string(&mpath).map_err(|e| LearnError::io(&mpath, e))?;
        let kept: Vec<&str> = text.lines().take(1 + rows as usize).collect();
        if kept.len() != 1 + rows as usize {
            return Err(LearnError::Config(format!(
                "{} has {} rows, the checkpoint expects {rows}",
                mpath.display(),
                kept.len().saturating_sub(1)
            )));
        }
        let mut body = kept.join("\n");
        body.push('\n');
        std::fs::write(&mpath, body).map_err(|e| LearnError::io(&mpath, e))?;
        let f = std::fs::OpenOptions::new()
            .append(true)
            .open(&mpath)
            .map_err(|e| LearnError::io(&mpath, e))?;
        Ok(RunDir {
            dir: dir.to_path_buf(),
            metrics: std::io::BufWriter::new(f),
        })
    }

    fn write_row(&mut self, row: &MetricsRow) -> Result<(), LearnError> {
        let p = self.dir.join("metrics.csv");
        writeln!(self.metrics, "{}", row.to_csv()).map_err(|e| LearnError::io(&p, e))?;
        self.metrics.flush().map_err(|e| LearnError::io(&p, e))
    }
}

/// What a finished run returns.
#[derive(Debug, Clone)]
pub struct TrainSummary {
    pub rows: Vec<MetricsRow>,
    pub transitions: u64,
    pub final_weights: PathBuf,
}

fn opponent_for(cfg: &TrainConfig) -> Result<Opponent, LearnError> {
    Ok(match &cfg.opponent {
        OpponentSpec::Builtin(name) => Opponent::Builtin(
            name.parse::<PolicyKind>()
                .map_err(|e| LearnError::Config(e.to_string()))?,
        ),
        OpponentSpec::Frozen(spec) => {
            let mut p = LearnedPolicy::load(spec)?;
            p.set_match_seed(cfg.seed);
            Opponent::Net(Box::new(p))
        }
        // The first snapshot is the untrained network, as in self-play from
        // scratch.
        OpponentSpec::SelfPlay { .. } => Opponent::Net(Box::new(self_play_snapshot(cfg, None)?)),
        // The schedule's runner sets the opponents once the learner exists.
        OpponentSpec::Schedule(_) if cfg.algo == Algo::Ppo => Opponent::Builtin(PolicyKind::Idle),
        OpponentSpec::Schedule(_) => {
            return Err(LearnError::Config(
                "opponent schedules are for PPO runs".into(),
            ))
        }
    })
}

fn make_env(cfg: &TrainConfig) -> Result<VecEnv, LearnError> {
    let supported = match cfg.algo {
        Algo::Ppo => layout_dim(cfg.obs_version).is_some(),
        Algo::Dqn => cfg.obs_version >= 2 && layout_dim(cfg.obs_version).is_some(),
    };
    if !supported {
        return Err(LearnError::Config(format!(
            "{} cannot train on observation layout v{} (this build encodes v1 to \
             v{OBS_VERSION_LATEST}; DQN trains on v2 and later)",
            cfg.algo, cfg.obs_version
        )));
    }
    if cfg.dqn.decision.is_some_and(|d| d.pass) {
        return Err(LearnError::Config(
            "the pass action is for PPO (--algo ppo --preset team) only".into(),
        ));
    }
    let decisions = [cfg.ppo.decision, cfg.dqn.decision];
    if decisions.iter().flatten().any(|d| d.support && !d.pass) {
        return Err(LearnError::Config(
            "the support action comes with the pass action (--pass-action --support-action)".into(),
        ));
    }
    if decisions
        .iter()
        .flatten()
        .any(|d| d.support_hold > 0 && !d.support)
    {
        return Err(LearnError::Config(
            "--support-hold holds the support action: it needs --support-action".into(),
        ));
    }
    if decisions
        .iter()
        .flatten()
        .any(|d| d.chasers > 0 && !d.support)
    {
        return Err(LearnError::Config(
            "--support-roles sends the robots away from the ball to support: it needs \
             --support-action"
                .into(),
        ));
    }
    if decisions
        .iter()
        .flatten()
        .any(|d| d.support_only && d.chasers == 0)
    {
        return Err(LearnError::Config(
            "--support-only applies to the robots that do not chase: it needs --support-roles"
                .into(),
        ));
    }
    if decisions
        .iter()
        .flatten()
        .any(|d| (d.approach || d.support_spot != Default::default()) && !d.support)
    {
        return Err(LearnError::Config(
            "--approach-action and --support-spot come with the support action: they need \
             --support-action"
                .into(),
        ));
    }
    if decisions
        .iter()
        .flatten()
        .any(|d| d.approach_only && !d.approach)
    {
        return Err(LearnError::Config(
            "--approach-only leaves the robots `approach` to move: it needs --approach-action"
                .into(),
        ));
    }
    if decisions.iter().flatten().any(|d| d.chasers >= 4) {
        return Err(LearnError::Config(
            "--support-roles names how many of the four robots chase: 1 to 3".into(),
        ));
    }
    if cfg.init_from.is_some() && (cfg.algo != Algo::Ppo || cfg.ppo.decision.is_none()) {
        return Err(LearnError::Config(
            "--init-from starts PPO team-preset runs (--algo ppo --preset team) only".into(),
        ));
    }
    if cfg.init_support_bias.is_some()
        && (cfg.init_from.is_none() || !cfg.ppo.decision.is_some_and(|d| d.support))
    {
        return Err(LearnError::Config(
            "--support-init-bias sets where a gained support row starts: it needs --init-from \
             and --support-action"
                .into(),
        ));
    }
    if cfg.init_support_bias.is_some_and(|b| !b.is_finite()) {
        return Err(LearnError::Config(
            "--support-init-bias must be a finite number".into(),
        ));
    }
    if cfg.init_pass_from.is_some()
        && (cfg.init_from.is_none() || !cfg.ppo.decision.is_some_and(|d| d.pass))
    {
        return Err(LearnError::Config(
            "--pass-init names where a gained pass row starts: it needs --init-from and --pass-action"
                .into(),
        ));
    }
    if cfg.ppo.decision.is_some() && cfg.obs_version < 2 {
        return Err(LearnError::Config(
            "the decision-level MDP needs observation layout v2 (busy flags, kick reach)".into(),
        ));
    }
    let teammates = cfg
        .teammates
        .parse::<PolicyKind>()
        .map_err(|e| LearnError::Config(e.to_string()))?;
    let mut env = VecEnv::new(
        &cfg.match_config,
        EnvConfig {
            matches: cfg.matches,
            learners: cfg.learners.clone(),
            teammates,
            threads: cfg.threads,
            seed: cfg.seed,
            support_spot: cfg
                .ppo
                .decision
                .map_or_else(Default::default, |d| d.support_spot),
        },
        opponent_for(cfg)?,
    )?;
    env.set_obs_scale(run_scale(cfg));
    if cfg.drill.is_some() {
        env.set_drill(cfg.drill)?;
    }
    if cfg.pass_drills.is_some() {
        if !matches!(cfg.algo, Algo::Ppo) || cfg.ppo.decision.is_none() {
            return Err(LearnError::Config(
                "pass drills need the PPO team preset (its loop bootstraps a drill's cut end)"
                    .into(),
            ));
        }
        env.set_pass_drills(cfg.pass_drills)?;
    }
    Ok(env)
}

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

fn checkpoint_due(before: u64, after: u64, every: u64) -> bool {
    every > 0 && before / every != after / every
}

fn snapshot_due(cfg: &TrainConfig, before: u64, after: u64) -> bool {
    matches!(cfg.opponent, OpponentSpec::SelfPlay { every } if checkpoint_due(before, after, every))
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
    let mut sched = start_schedule(cfg, out, &mut env, &ppo)?;
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

/// The opponent schedule's runner, when the run has one.
fn start_schedule(
    cfg: &TrainConfig,
    out: &Path,
    env: &mut VecEnv,
    ppo: &Ppo,
) -> Result<Option<ScheduleRunner>, LearnError> {
    match &cfg.opponent {
        OpponentSpec::Schedule(s) => Ok(Some(ScheduleRunner::start(
            s,
            cfg,
            out,
            env,
            &[&ppo.net.vs],
        )?)),
        _ => Ok(None),
    }
}

/// The open transition of one learning robot: from its last decision until
/// its next (decision-level MDP).
#[derive(Debug, Clone, Copy, Default)]
struct Pending {
    open: bool,
    action: usize,
    logp: f32,
    value: f32,
    shoot_ok: bool,
    /// [`banned_actions`] at the decision.
    banned: u8,
    /// `sum gamma^i r_i` so far, and `gamma^elapsed`.
    reward: f32,
    discount: f32,
    elapsed: u32,
    /// The closed transition that leads into this one (same robot, same
    /// episode, same rollout).
    prev: Option<usize>,
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
    let half = [scale.half_length, scale.half_width];
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
            let sched = start_schedule(cfg, out, &mut env, &ppo)?;
            if matches!(cfg.opponent, OpponentSpec::SelfPlay { .. }) {
                let name = "self-play-step-0.safetensors".to_string();
                set_self_play(cfg, out, &name, Some(&ppo), &mut env)?;
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
    let gamma = cfg.ppo.gamma as f32;
    let cw = ppo.net.critic_dim;
    let mut tr = Transitions::default();
    let mut holds = vec![Hold::default(); rows];
    let mut pend = vec![Pending::default(); rows];
    let mut pend_obs = vec![0.0f32; rows * OBS_DIM];
    let mut pend_cobs = vec![0.0f32; rows * cw];
    let mut actions = vec![0usize; rows];
    // Scratch for the deciding rows of a tick.
    let (mut dec_rows, mut dec_obs, mut dec_cobs, mut dec_ok) =
        (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    let (mut dec_act, mut dec_logp, mut dec_val) = (Vec::new(), Vec::new(), Vec::new());
    // What each deciding robot may not choose beyond a `shoot` out of
    // reach (`pass` without a receiver, roles; nothing without them).
    let mut dec_banned = Vec::new();
    let (mut cut_rows, mut cut_cobs, mut cut_val) = (Vec::new(), Vec::new(), Vec::new());
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
            dec_rows.clear();
            dec_obs.clear();
            dec_cobs.clear();
            dec_ok.clear();
            dec_banned.clear();
            for (r, hold) in holds.iter_mut().enumerate() {
                let o = env.learner_observation(r);
                if hold.must_decide(o) {
                    dec_rows.push(r);
                    dec_obs.extend_from_slice(&env.observations()[r * OBS_DIM..(r + 1) * OBS_DIM]);
                    push_critic_row(env.observations(), l, r, scale.dim(), cw, &mut dec_cobs);
                    dec_ok.push(!cfg.ppo.masks_shoot() || scale.kick.in_reach(o));
                    dec_banned.push(banned_actions(o, scale.kick.in_reach(o), &decision));
                } else {
                    actions[r] = hold.held(o);
                }
            }
            let k = dec_rows.len();
            dec_act.resize(k, 0);
            dec_logp.resize(k, 0.0);
            dec_val.resize(k, 0.0);
            ppo.act_masked(
                &dec_obs,
                &dec_ok,
                &dec_banned,
                &mut rng,
                &mut dec_act,
                &mut dec_logp,
            );
            ppo.critic_values(&dec_cobs, &mut dec_val);
            for (j, &r) in dec_rows.iter().enumerate() {
                let prev = close_pending(
                    &mut tr,
                    &mut pend[r],
                    &pend_obs[r * OBS_DIM..(r + 1) * OBS_DIM],
                    &pend_cobs[r * cw..(r + 1) * cw],
                    dec_val[j],
                    false,
                );
                pend[r] = Pending {
                    open: true,
                    action: dec_act[j],
                    logp: dec_logp[j],
                    value: dec_val[j],
                    shoot_ok: dec_ok[j],
                    banned: dec_banned[j],
                    reward: 0.0,
                    discount: 1.0,
                    elapsed: 0,
                    prev,
                };
                pend_obs[r * OBS_DIM..(r + 1) * OBS_DIM]
                    .copy_from_slice(&dec_obs[j * OBS_DIM..(j + 1) * OBS_DIM]);
                pend_cobs[r * cw..(r + 1) * cw].copy_from_slice(&dec_cobs[j * cw..(j + 1) * cw]);
                let tick = env.learner_observation(r).tick;
                holds[r].start(dec_act[j], tick, &decision, half);
                actions[r] = dec_act[j];
            }
            let finished = env.step(&actions)?;
            // Episodes cut short (pass drills) are bootstrapped with the
            // critic's value of the state where they were cut.
            cut_rows.clear();
            cut_cobs.clear();
            for r in 0..rows {
                if env.truncated()[r] {
                    cut_rows.push(r);
                    push_critic_row(
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
            let mut cut = cut_rows.iter().zip(&cut_val).peekable();
            for (r, p) in pend.iter_mut().enumerate() {
                if p.open {
                    p.reward += p.discount * env.rewards()[r];
                    p.discount *= gamma;
                    p.elapsed += 1;
                }
                if env.dones()[r] {
                    let bootstrap = cut.next_if(|(&c, _)| c == r).map(|(_, &v)| v);
                    close_pending(
                        &mut tr,
                        p,
                        &pend_obs[r * OBS_DIM..(r + 1) * OBS_DIM],
                        &pend_cobs[r * cw..(r + 1) * cw],
                        bootstrap.unwrap_or(0.0),
                        bootstrap.is_none(),
                    );
                    holds[r].reset();
                }
            }
            tally.add_rewards(env.rewards());
            tally.episodes.extend(finished);
            boundary = env.dones().iter().all(|&d| d);
        }
        // The rollout's edge: open transitions end here, bootstrapped with
        // the critic's value of the state they reached.
        let mut edge_cobs = Vec::with_capacity(rows * cw);
        for r in 0..rows {
            push_critic_row(env.observations(), l, r, scale.dim(), cw, &mut edge_cobs);
        }
        let mut edge_val = vec![0.0f32; rows];
        ppo.critic_values(&edge_cobs, &mut edge_val);
        for r in 0..rows {
            close_pending(
                &mut tr,
                &mut pend[r],
                &pend_obs[r * OBS_DIM..(r + 1) * OBS_DIM],
                &pend_cobs[r * cw..(r + 1) * cw],
                edge_val[r],
                false,
            );
            pend[r].prev = None;
        }
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
            set_self_play(cfg, out, &name, Some(&ppo), &mut env)?;
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
            write_checkpoint(out, &ppo, &state)?;
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

/// Loads `path`'s weights (a run's `final.safetensors` or a checkpoint, or
/// a run directory holding `final.safetensors`) into `ppo`'s networks. Every
/// variable must be there with its shape, except that an actor with the
/// `pass` action may start from one without it: its extra output row (the
/// last layer's weights and bias) starts as a copy of `pass_from`'s (with
/// `shoot`, `pass` is at first as likely as `shoot` where both are
/// possible). `pass_from` must be one of the paper's five actions. A gained
/// `support` row starts as `forward`'s with its bias `support_bias` lower,
/// a gained `approach` row as an exact copy of `forward`'s.
pub fn init_weights(
    ppo: &mut Ppo,
    path: &Path,
    pass_from: naosoccer_proto::Action,
    support_bias: f32,
) -> Result<(), LearnError> {
    use crate::ppo::PASS;
    use naosoccer_policy::{APPROACH, SUPPORT};
    let file = if path.is_dir() {
        path.join("final.safetensors")
    } else {
        path.to_path_buf()
    };
    let bad =
        |reason: String| LearnError::Config(format!("--init-from {}: {reason}", file.display()));
    if !file.is_file() {
        return Err(bad("no such weights file".into()));
    }
    let pass_row = pass_from.index();
    if pass_row >= PASS {
        return Err(bad(format!(
            "pass cannot start as a copy of {:?}: pick one of the five actions the source has",
            pass_from.name()
        )));
    }
    let named: std::collections::BTreeMap<String, tch::Tensor> =
        tch::Tensor::read_safetensors(&file)?.into_iter().collect();
    let mut vars: Vec<(String, tch::Tensor)> = ppo.net.vs.variables().into_iter().collect();
    vars.sort_by(|a, b| a.0.cmp(&b.0));
    for (name, mut var) in vars {
        let src = named
            .get(&name)
            .ok_or_else(|| bad(format!("no tensor {name:?} (a run of another shape?)")))?;
        let (want, got) = (var.size(), src.size());
        tch::no_grad(|| -> Result<(), LearnError> {
            // The actor's output layer may gain rows: `pass` (a copy of
            // `pass_from`, by default `shoot`), `support` (a copy of
            // `forward`, its bias lowered by `support_bias`, by default
            // SUPPORT_INIT_BIAS so that it starts rarer than `forward`) and
            // `approach` (an exact copy of `forward`).
            let (pass, support, approach) = (PASS as i64, SUPPORT as i64, APPROACH as i64);
            let widen = name.starts_with("actor.")
                && !want.is_empty()
                && want[1..] == got[1..]
                && (pass..=approach).contains(&got[0])
                && (pass + 1..=approach + 1).contains(&want[0])
                && want[0] > got[0];
            if want == got {
                var.copy_(src);
            } else if widen {
                var.narrow(0, 0, got[0]).copy_(src);
                let forward = src.narrow(0, naosoccer_policy::actions::FORWARD as i64, 1);
                if got[0] <= pass {
                    var.narrow(0, pass, 1)
                        .copy_(&src.narrow(0, pass_row as i64, 1));
                }
                if got[0] <= support && want[0] > support {
                    let row = if want.len() == 1 {
                        &forward - f64::from(support_bias)
                    } else {
                        forward.shallow_clone()
                    };
                    var.narrow(0, support, 1).copy_(&row);
                }
                if want[0] > approach {
                    var.narrow(0, approach, 1).copy_(&forward);
                }
            } else {
                return Err(bad(format!(
                    "{name} is {got:?} there, the run's network needs {want:?}"
                )));
            }
            Ok(())
        })?;
    }
    Ok(())
}

/// How much lower `support`'s bias starts than `forward`'s when
/// `--init-from` widens an actor: e^-1, about 2.7 times less likely.
pub const SUPPORT_INIT_BIAS: f32 = 1.0;

/// Where a decision-level run stands at a checkpoint (an episode boundary):
/// with the weights (`step-N.safetensors`) and the optimiser's moments
/// (`step-N.adam.safetensors`), everything `train --resume` needs to go on
/// as if the run had not stopped. Saved as `checkpoints/step-N.resume.json`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ResumeState {
    pub transitions: u64,
    pub update: u64,
    pub env_ticks: u64,
    /// Each match's next episode number.
    pub episodes: Vec<u64>,
    pub total_episodes: u64,
    /// The ChaCha8 stream (sampling, minibatch order): seed, stream and
    /// word position (a decimal string: it is a u128).
    pub rng_seed: [u8; 32],
    pub rng_stream: u64,
    pub rng_word_pos: String,
    pub value_norm: crate::ppo::RunningNorm,
    /// The opponent schedule's stage and snapshot pool.
    pub schedule: Option<(usize, Vec<(u64, String)>)>,
    /// The self-play snapshot in play (a file in `pool/`).
    pub self_play: Option<String>,
}

impl ResumeState {
    fn rng(&self) -> Result<ChaCha8Rng, LearnError> {
        let mut r = ChaCha8Rng::from_seed(self.rng_seed);
        r.set_stream(self.rng_stream);
        r.set_word_pos(self.rng_word_pos.parse::<u128>().map_err(|_| {
            LearnError::Config(format!("bad RNG position {:?}", self.rng_word_pos))
        })?);
        Ok(r)
    }
}

fn write_checkpoint(out: &Path, ppo: &Ppo, state: &ResumeState) -> Result<(), LearnError> {
    let ck = out.join("checkpoints");
    let n = state.transitions;
    save_stores(&[&ppo.net.vs], &ck.join(format!("step-{n}.safetensors")))?;
    if let Some(a) = &ppo.adam {
        tch::Tensor::write_safetensors(&a.state(), ck.join(format!("step-{n}.adam.safetensors")))?;
    }
    let path = ck.join(format!("step-{n}.resume.json"));
    let json = serde_json::to_string_pretty(state).map_err(|e| LearnError::json(&path, e))?;
    // Written last: a checkpoint counts once its resume state exists.
    std::fs::write(&path, json).map_err(|e| LearnError::io(&path, e))
}

/// Makes `pool/NAME` the self-play opponent, writing the live weights
/// there first when `live` is given.
fn set_self_play(
    cfg: &TrainConfig,
    out: &Path,
    name: &str,
    live: Option<&Ppo>,
    env: &mut VecEnv,
) -> Result<(), LearnError> {
    let dir = out.join("pool");
    std::fs::create_dir_all(&dir).map_err(|e| LearnError::io(&dir, e))?;
    let path = dir.join(name);
    if let Some(p) = live {
        save_stores(&[&p.net.vs], &path)?;
    }
    let mut snap = self_play_snapshot(cfg, None)?;
    snap.load_weights(&path)?;
    env.set_opponent(Opponent::Net(Box::new(snap)));
    Ok(())
}

/// Continues the run in `dir` from its latest resumable checkpoint, as if
/// it had not stopped (decision-level PPO runs; `steps`, if given, replaces
/// the run's length). metrics.csv keeps the rows up to that checkpoint.
pub fn resume(
    dir: &Path,
    steps: Option<u64>,
    progress: &mut dyn FnMut(&Progress<'_>),
) -> Result<TrainSummary, LearnError> {
    let cfg_path = dir.join("config.json");
    let text = std::fs::read_to_string(&cfg_path).map_err(|e| LearnError::io(&cfg_path, e))?;
    let mut cfg: TrainConfig =
        serde_json::from_str(&text).map_err(|e| LearnError::json(&cfg_path, e))?;
    if cfg.algo != Algo::Ppo || cfg.ppo.decision.is_none() {
        return Err(LearnError::Config(
            "--resume continues decision-level PPO runs (--preset team) only".into(),
        ));
    }
    if let Some(s) = steps {
        cfg.steps = s;
        let json =
            serde_json::to_string_pretty(&cfg).map_err(|e| LearnError::json(&cfg_path, e))?;
        std::fs::write(&cfg_path, json).map_err(|e| LearnError::io(&cfg_path, e))?;
    }
    let ck = dir.join("checkpoints");
    let mut best: Option<u64> = None;
    if let Ok(rd) = std::fs::read_dir(&ck) {
        for e in rd.flatten() {
            let name = e.file_name().to_string_lossy().into_owned();
            if let Some(n) = name
                .strip_prefix("step-")
                .and_then(|n| n.strip_suffix(".resume.json"))
                .and_then(|n| n.parse::<u64>().ok())
            {
                best = best.max(Some(n));
            }
        }
    }
    let n = best.ok_or_else(|| naosoccer_policy::PolicyError::Spec {
        spec: dir.display().to_string(),
        reason: "no checkpoints/step-N.resume.json to resume from".into(),
    })?;
    let path = ck.join(format!("step-{n}.resume.json"));
    let text = std::fs::read_to_string(&path).map_err(|e| LearnError::io(&path, e))?;
    let state: ResumeState = serde_json::from_str(&text).map_err(|e| LearnError::json(&path, e))?;
    tch::manual_seed(cfg.seed as i64);
    train_ppo_decisions(&cfg, dir, Some(state), progress)
}

/// Closes `p` (if open) into `tr` with the value `next_value` after it;
/// returns the closed transition's index when the robot's stream goes on
/// from it (not at an episode's end).
fn close_pending(
    tr: &mut Transitions,
    p: &mut Pending,
    obs: &[f32],
    cobs: &[f32],
    next_value: f32,
    done: bool,
) -> Option<usize> {
    if !p.open {
        return None;
    }
    let i = tr.len();
    tr.obs.extend_from_slice(obs);
    tr.critic_obs.extend_from_slice(cobs);
    tr.actions.push(p.action as i64);
    tr.logp.push(p.logp);
    tr.shoot_ok.push(p.shoot_ok);
    tr.banned.push(p.banned);
    tr.values.push(p.value);
    tr.rewards.push(p.reward);
    tr.dt.push(p.elapsed.max(1));
    tr.next_values.push(next_value);
    tr.dones.push(done);
    tr.next.push(None);
    if let Some(j) = p.prev {
        tr.next[j] = Some(i);
    }
    p.open = false;
    p.prev = None;
    (!done).then_some(i)
}

/// Appends row `r`'s critic input: its own observation vector (the layout's
/// `dim` entries), then, with a centralised critic (`cw` > `dim`), those of
/// the other learning robots of its match in order.
fn push_critic_row(feats: &[f32], l: usize, r: usize, dim: usize, cw: usize, out: &mut Vec<f32>) {
    let row = |i: usize| &feats[i * OBS_DIM..i * OBS_DIM + dim];
    out.extend_from_slice(row(r));
    if cw > dim {
        let base = r / l * l;
        for k in 0..l {
            if base + k != r {
                out.extend_from_slice(row(base + k));
            }
        }
    }
}

/// One robot's decision in progress (decision-level DQN).
#[derive(Debug, Clone, Copy, Default)]
struct OpenDecision {
    open: bool,
    action: usize,
    /// `sum gamma^i r_i` so far, and `gamma^elapsed`.
    reward: f32,
    discount: f32,
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
    let half = [scale.half_length, scale.half_width];
    let robots = cfg.learners.len();
    let mut dqn = Dqn::new(cfg.dqn.clone(), robots, run_scale(cfg).dim())?;
    let mut rng = ChaCha8Rng::seed_from_u64(cfg.seed);
    let rows = env.rows();
    let mut tally = Tally::new(robots);
    let mut actions = vec![0usize; rows];
    let mut holds = vec![Hold::default(); rows];
    let mut open = vec![OpenDecision::default(); rows];
    let mut open_obs = vec![0.0f32; rows * OBS_DIM];
    let mut deciding = vec![false; rows];
    let mut shoot_ok = vec![true; rows];
    let mut q = Vec::new();
    let mut nstep = NStep::new(cfg.dqn.n_step, rows);
    let gamma = cfg.dqn.discount(1);
    let mut log = DqnLog::default();
    while log.transitions < cfg.steps {
        let mut any = false;
        for r in 0..rows {
            let o = env.learner_observation(r);
            shoot_ok[r] = !decision.mask_shoot || scale.kick.in_reach(o);
            deciding[r] = holds[r].must_decide(o);
            if !deciding[r] {
                actions[r] = holds[r].held(o);
            }
            any |= deciding[r];
        }
        if any {
            let obs = env.observations();
            dqn.q_values(obs, robots, &mut q);
            let epsilon = cfg.dqn.epsilon_at(log.transitions);
            for r in (0..rows).filter(|&r| deciding[r]) {
                let row = &obs[r * OBS_DIM..(r + 1) * OBS_DIM];
                // The decision that ran until now ends in this state.
                let d = open[r];
                if d.open {
                    let ok = shoot_ok[r];
                    nstep.push(
                        r,
                        &open_obs[r * OBS_DIM..(r + 1) * OBS_DIM],
                        d.action,
                        d.reward,
                        d.discount,
                        false,
                        &mut |t| {
                            dqn.remember(r % robots, t.obs, t.action, t.ret, row, t.discount, ok)
                        },
                    );
                }
                let a = epsilon_greedy(
                    &q[r * ACTIONS..(r + 1) * ACTIONS],
                    shoot_ok[r],
                    epsilon,
                    &mut rng,
                );
                open[r] = OpenDecision {
                    open: true,
                    action: a,
                    reward: 0.0,
                    discount: 1.0,
                };
                open_obs[r * OBS_DIM..(r + 1) * OBS_DIM].copy_from_slice(row);
                holds[r].start(a, env.learner_observation(r).tick, &decision, half);
                actions[r] = a;
            }
        }
        let finished = env.step(&actions)?;
        for r in 0..rows {
            let d = &mut open[r];
            if d.open {
                d.reward += d.discount * env.rewards()[r];
                d.discount *= gamma;
            }
            if env.dones()[r] {
                if d.open {
                    let d = *d;
                    // Terminal: the next observation is never bootstrapped from.
                    let row = &open_obs[r * OBS_DIM..(r + 1) * OBS_DIM];
                    nstep.push(r, row, d.action, d.reward, d.discount, true, &mut |t| {
                        dqn.remember(r % robots, t.obs, t.action, t.ret, row, t.discount, true)
                    });
                }
                open[r].open = false;
                holds[r].reset();
            }
        }
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
