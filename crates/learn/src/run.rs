//! The run harness: what a training run needs that is not the algorithm.
//! It owns the run directory (`config.json`, `metrics.csv`, checkpoints,
//! the snapshot pool), builds the environment and its opponents from the
//! configuration, keeps the self-play opponent and the opponent schedule
//! up to date, and finds where a stopped run resumes. The learners
//! ([`crate::train`]) call it; it knows no algorithm, only the networks'
//! variable stores.
//!
//! A run directory:
//! - `config.json`: the run's [`TrainConfig`] (networks, hyperparameters,
//!   match configuration, observation layout version and scale),
//! - `metrics.csv`: one row per update (PPO) or log interval (DQN),
//! - `checkpoints/step-N.safetensors` every `checkpoint_every` transitions
//!   (decision-level PPO also `step-N.adam.safetensors` and
//!   `step-N.resume.json`, at episode boundaries),
//! - `pool/`: self-play and schedule snapshots,
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
use tch::nn::VarStore;

use crate::adam::Adam;
use crate::config::{run_scale, Algo, OpponentSpec, TrainConfig};
use crate::env::{EnvConfig, Episode, Opponent, VecEnv};
use crate::obs::{layout_dim, OBS_VERSION_LATEST};
use crate::policy::{save_stores, self_play_snapshot, LearnedPolicy};
use crate::schedule_runner::ScheduleRunner;
use crate::LearnError;

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
pub(crate) struct Tally {
    robots: usize,
    reward_sum: Vec<f64>,
    samples: u64,
    pub(crate) episodes: Vec<Episode>,
    pub(crate) total_episodes: u64,
}

impl Tally {
    pub(crate) fn new(robots: usize) -> Tally {
        Tally {
            robots,
            reward_sum: vec![0.0; robots],
            samples: 0,
            episodes: Vec::new(),
            total_episodes: 0,
        }
    }

    pub(crate) fn add_rewards(&mut self, rewards: &[f32]) {
        for (i, r) in rewards.iter().enumerate() {
            self.reward_sum[i % self.robots] += f64::from(*r);
        }
        self.samples += (rewards.len() / self.robots) as u64;
    }

    pub(crate) fn row(
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
pub(crate) struct RunDir {
    dir: PathBuf,
    metrics: std::io::BufWriter<std::fs::File>,
}

impl RunDir {
    pub(crate) fn create(dir: &Path, cfg: &TrainConfig) -> Result<RunDir, LearnError> {
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
    pub(crate) fn reopen(dir: &Path, rows: u64) -> Result<RunDir, LearnError> {
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

    pub(crate) fn write_row(&mut self, row: &MetricsRow) -> Result<(), LearnError> {
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

pub(crate) fn make_env(cfg: &TrainConfig) -> Result<VecEnv, LearnError> {
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

pub(crate) fn checkpoint_due(before: u64, after: u64, every: u64) -> bool {
    every > 0 && before / every != after / every
}

pub(crate) fn snapshot_due(cfg: &TrainConfig, before: u64, after: u64) -> bool {
    matches!(cfg.opponent, OpponentSpec::SelfPlay { every } if checkpoint_due(before, after, every))
}

/// The opponent schedule's runner, when the run has one.
pub(crate) fn start_schedule(
    cfg: &TrainConfig,
    out: &Path,
    env: &mut VecEnv,
    live: &[&VarStore],
) -> Result<Option<ScheduleRunner>, LearnError> {
    match &cfg.opponent {
        OpponentSpec::Schedule(s) => Ok(Some(ScheduleRunner::start(s, cfg, out, env, live)?)),
        _ => Ok(None),
    }
}

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
    pub(crate) fn rng(&self) -> Result<ChaCha8Rng, LearnError> {
        let mut r = ChaCha8Rng::from_seed(self.rng_seed);
        r.set_stream(self.rng_stream);
        r.set_word_pos(self.rng_word_pos.parse::<u128>().map_err(|_| {
            LearnError::Config(format!("bad RNG position {:?}", self.rng_word_pos))
        })?);
        Ok(r)
    }
}

/// Writes a resumable checkpoint: the weights of `live`, the optimiser's
/// moments and `state`.
pub(crate) fn write_checkpoint(
    out: &Path,
    live: &VarStore,
    adam: Option<&Adam>,
    state: &ResumeState,
) -> Result<(), LearnError> {
    let ck = out.join("checkpoints");
    let n = state.transitions;
    save_stores(&[live], &ck.join(format!("step-{n}.safetensors")))?;
    if let Some(a) = adam {
        tch::Tensor::write_safetensors(&a.state(), ck.join(format!("step-{n}.adam.safetensors")))?;
    }
    let path = ck.join(format!("step-{n}.resume.json"));
    let json = serde_json::to_string_pretty(state).map_err(|e| LearnError::json(&path, e))?;
    // Written last: a checkpoint counts once its resume state exists.
    std::fs::write(&path, json).map_err(|e| LearnError::io(&path, e))
}

/// Makes `pool/NAME` the self-play opponent, writing the live weights
/// there first when `live` is given.
pub(crate) fn set_self_play(
    cfg: &TrainConfig,
    out: &Path,
    name: &str,
    live: Option<&VarStore>,
    env: &mut VecEnv,
) -> Result<(), LearnError> {
    let dir = out.join("pool");
    std::fs::create_dir_all(&dir).map_err(|e| LearnError::io(&dir, e))?;
    let path = dir.join(name);
    if let Some(p) = live {
        save_stores(&[p], &path)?;
    }
    let mut snap = self_play_snapshot(cfg, None)?;
    snap.load_weights(&path)?;
    env.set_opponent(Opponent::Net(Box::new(snap)));
    Ok(())
}

/// The configuration of the run in `dir` (its length replaced by `steps`,
/// if given, and saved so) and the state of its latest resumable
/// checkpoint (decision-level PPO runs).
pub(crate) fn resume_point(
    dir: &Path,
    steps: Option<u64>,
) -> Result<(TrainConfig, ResumeState), LearnError> {
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
    Ok((cfg, state))
}
