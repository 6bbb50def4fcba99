//! The run harness: what a training run needs that is not the algorithm.
//! A learner drives one [`Run`]: it reports rewards and finished episodes
//! every tick and a metrics row every update; the run writes the run
//! directory, refreshes the opponents (self-play snapshots, the opponent
//! schedule), takes checkpoints when they fall due, and on resume puts
//! everything but the learner's own state back. It knows no algorithm,
//! only the networks' variable stores.
//!
//! - this file: [`Run`], the run directory and the metrics it writes;
//! - [`setup`]: the environment and its first opponents, from the
//!   configuration (and the checks of what a configuration may combine);
//! - [`resume`]: resumable checkpoints, and where a stopped run goes on.
//!
//! A run directory:
//! - `config.json`: the run's [`TrainConfig`] (networks, hyperparameters,
//!   match configuration, observation layout version and scale),
//! - `metrics.csv`: one row per update (PPO) or log interval (DQN),
//! - `checkpoints/step-N.safetensors` every `checkpoint_every` transitions
//!   (team-preset PPO also `step-N.adam.safetensors` and
//!   `step-N.resume.json`, at episode boundaries),
//! - `pool/`: self-play and schedule snapshots,
//! - `final.safetensors` at the end.
//!
//! Nothing here reads the clock: the same configuration, seed and thread
//! count write the same metrics.

pub mod resume;
pub mod setup;

use std::io::Write;
use std::path::{Path, PathBuf};

use rand_chacha::ChaCha8Rng;
use tch::nn::VarStore;

use crate::adam::Adam;
use crate::config::{OpponentSpec, TrainConfig};
use crate::env::{Episode, Opponent, VecEnv};
use crate::metrics::{MetricsRow, Progress, Tally};
use crate::nets::RunningNorm;
use crate::policy::{save_stores, self_play_snapshot};
use crate::schedule_runner::ScheduleRunner;
use crate::LearnError;

pub use resume::ResumeState;
pub(crate) use setup::make_env;

/// A training run as a learner drives it: the run directory and the
/// metrics rows written so far, the transition count, the opponents it
/// keeps up to date and the checkpoints it has taken.
pub struct Run<'a> {
    cfg: &'a TrainConfig,
    out: &'a Path,
    dir: RunDir,
    tally: Tally,
    transitions: u64,
    /// Metrics rows written (for PPO, updates).
    update: u64,
    rows: Vec<MetricsRow>,
    progress: &'a mut dyn FnMut(&Progress<'_>),
    sched: Option<ScheduleRunner>,
    /// A resumable run keeps its self-play snapshots as files in `pool/`
    /// (a resume reloads the one in play, named here); the others hand
    /// them to the environment directly.
    resumable: bool,
    self_play: Option<String>,
    last_checkpoint: u64,
}

impl<'a> Run<'a> {
    /// Starts a run in `out`: writes `config.json` and the metrics header,
    /// and gives `env` the schedule's first opponents (and a resumable
    /// run's first self-play snapshot). `live`: the learner's networks.
    pub(crate) fn start(
        cfg: &'a TrainConfig,
        out: &'a Path,
        env: &mut VecEnv,
        live: &[&VarStore],
        resumable: bool,
        progress: &'a mut dyn FnMut(&Progress<'_>),
    ) -> Result<Run<'a>, LearnError> {
        let dir = RunDir::create(out, cfg)?;
        let sched = match &cfg.opponent {
            OpponentSpec::Schedule(s) => Some(ScheduleRunner::start(s, cfg, out, env, live)?),
            _ => None,
        };
        let mut run = Run::new(cfg, out, dir, sched, resumable, progress);
        if resumable && matches!(cfg.opponent, OpponentSpec::SelfPlay { .. }) {
            run.set_self_play("self-play-step-0.safetensors", Some(live), env)?;
        }
        Ok(run)
    }

    /// Goes on from the resumable checkpoint `st` of the run in `out`:
    /// the counters, the matches, the opponents and `metrics.csv` as they
    /// were then. The learner restores its own state
    /// ([`resume::read_checkpoint`], [`ResumeState::rng`]).
    pub(crate) fn resume(
        cfg: &'a TrainConfig,
        out: &'a Path,
        st: &ResumeState,
        env: &mut VecEnv,
        progress: &'a mut dyn FnMut(&Progress<'_>),
    ) -> Result<Run<'a>, LearnError> {
        env.restart_at(&st.episodes, st.env_ticks)?;
        let sched = match (&cfg.opponent, &st.schedule) {
            (OpponentSpec::Schedule(s), Some(state)) => {
                Some(ScheduleRunner::resume(s, cfg, out, env, state)?)
            }
            _ => None,
        };
        if let Some(name) = &st.self_play {
            self_play_from_pool(cfg, out, name, None, env)?;
        }
        let dir = RunDir::reopen(out, st.update)?;
        let mut run = Run::new(cfg, out, dir, sched, true, progress);
        run.transitions = st.transitions;
        run.last_checkpoint = st.transitions;
        run.update = st.update;
        run.tally.total_episodes = st.total_episodes;
        run.self_play = st.self_play.clone();
        Ok(run)
    }

    fn new(
        cfg: &'a TrainConfig,
        out: &'a Path,
        dir: RunDir,
        sched: Option<ScheduleRunner>,
        resumable: bool,
        progress: &'a mut dyn FnMut(&Progress<'_>),
    ) -> Run<'a> {
        Run {
            cfg,
            out,
            dir,
            tally: Tally::new(cfg.learners.len()),
            transitions: 0,
            update: 0,
            rows: Vec::new(),
            progress,
            sched,
            resumable,
            self_play: None,
            last_checkpoint: 0,
        }
    }

    /// Transitions so far.
    pub(crate) fn transitions(&self) -> u64 {
        self.transitions
    }

    /// Whether the run has its `steps` transitions.
    pub(crate) fn done(&self) -> bool {
        self.transitions >= self.cfg.steps
    }

    /// A tick's rewards and the episodes that ended in it, for the next
    /// metrics row.
    pub(crate) fn observe(&mut self, rewards: &[f32], finished: Vec<Episode>) {
        self.tally.add_rewards(rewards);
        self.tally.episodes.extend(finished);
    }

    /// Counts `n` more transitions; returns the count before them.
    pub(crate) fn count(&mut self, n: usize) -> u64 {
        let before = self.transitions;
        self.transitions += n as u64;
        before
    }

    /// Writes a metrics row (the losses: PPO's policy and value losses and
    /// entropy, DQN's TD loss and two NaNs) and reports it.
    pub(crate) fn log(&mut self, env: &VecEnv, losses: (f64, f64, f64)) -> Result<(), LearnError> {
        self.update += 1;
        let timeslot = env.ticks() / self.cfg.matches as u64;
        let row = self
            .tally
            .row(self.update, timeslot, self.transitions, losses);
        self.dir.write_row(&row)?;
        (self.progress)(&Progress {
            row: &row,
            total_steps: self.cfg.steps,
        });
        self.rows.push(row);
        Ok(())
    }

    /// After the run went from `before` transitions to its count now: a
    /// self-play snapshot of `live` when one is due, and the schedule's
    /// next snapshot or stage.
    pub(crate) fn refresh_opponents(
        &mut self,
        before: u64,
        env: &mut VecEnv,
        live: &[&VarStore],
    ) -> Result<(), LearnError> {
        let after = self.transitions;
        if snapshot_due(self.cfg, before, after) {
            if self.resumable {
                let name = format!("self-play-step-{after}.safetensors");
                self.set_self_play(&name, Some(live), env)?;
            } else {
                let snap = self_play_snapshot(self.cfg, Some(live))?;
                env.set_opponent(Opponent::Net(Box::new(snap)));
            }
        }
        if let Some(sc) = self.sched.as_mut() {
            sc.advance(self.cfg, before, after, env, live)?;
        }
        Ok(())
    }

    /// Whether `checkpoint_every` transitions passed since the last
    /// checkpoint (or the start).
    pub(crate) fn checkpoint_due(&self) -> bool {
        checkpoint_due(
            self.last_checkpoint,
            self.transitions,
            self.cfg.checkpoint_every,
        )
    }

    /// Saves `live` as `checkpoints/step-N.safetensors`.
    pub(crate) fn checkpoint(&mut self, live: &[&VarStore]) -> Result<(), LearnError> {
        self.last_checkpoint = self.transitions;
        let name = format!("checkpoints/step-{}.safetensors", self.transitions);
        save_stores(live, &self.out.join(name))
    }

    /// A resumable checkpoint (at an episode boundary): `live`, the
    /// optimiser's moments and everything else a resume needs
    /// ([`ResumeState`]).
    pub(crate) fn checkpoint_resumable(
        &mut self,
        env: &VecEnv,
        rng: &ChaCha8Rng,
        live: &VarStore,
        adam: Option<&Adam>,
        value_norm: RunningNorm,
    ) -> Result<(), LearnError> {
        self.last_checkpoint = self.transitions;
        let state = ResumeState {
            transitions: self.transitions,
            update: self.update,
            env_ticks: env.ticks(),
            episodes: env.episodes(),
            total_episodes: self.tally.total_episodes,
            rng_seed: rng.get_seed(),
            rng_stream: rng.get_stream(),
            rng_word_pos: rng.get_word_pos().to_string(),
            value_norm,
            schedule: self.sched.as_ref().map(ScheduleRunner::state),
            self_play: self.self_play.clone(),
        };
        resume::write_checkpoint(self.out, live, adam, &state)
    }

    /// Saves `live` as `final.safetensors` and sums the run up.
    pub(crate) fn finish(self, live: &[&VarStore]) -> Result<TrainSummary, LearnError> {
        let final_weights = self.out.join("final.safetensors");
        save_stores(live, &final_weights)?;
        Ok(TrainSummary {
            rows: self.rows,
            transitions: self.transitions,
            final_weights,
        })
    }

    fn set_self_play(
        &mut self,
        name: &str,
        live: Option<&[&VarStore]>,
        env: &mut VecEnv,
    ) -> Result<(), LearnError> {
        self_play_from_pool(self.cfg, self.out, name, live, env)?;
        self.self_play = Some(name.to_string());
        Ok(())
    }
}

/// Makes `pool/NAME` the self-play opponent, writing the live weights
/// there first when `live` is given.
fn self_play_from_pool(
    cfg: &TrainConfig,
    out: &Path,
    name: &str,
    live: Option<&[&VarStore]>,
    env: &mut VecEnv,
) -> Result<(), LearnError> {
    let dir = out.join("pool");
    std::fs::create_dir_all(&dir).map_err(|e| LearnError::io(&dir, e))?;
    let path = dir.join(name);
    if let Some(p) = live {
        save_stores(p, &path)?;
    }
    let mut snap = self_play_snapshot(cfg, None)?;
    snap.load_weights(&path)?;
    env.set_opponent(Opponent::Net(Box::new(snap)));
    Ok(())
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

fn checkpoint_due(before: u64, after: u64, every: u64) -> bool {
    every > 0 && before / every != after / every
}

fn snapshot_due(cfg: &TrainConfig, before: u64, after: u64) -> bool {
    matches!(cfg.opponent, OpponentSpec::SelfPlay { every } if checkpoint_due(before, after, every))
}
