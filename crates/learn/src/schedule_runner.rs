//! An opponent schedule as a run plays it (see [`crate::schedule`] for what
//! a schedule says): the stage in force, the pool of the learner's
//! snapshots, and the environment's opponents rebuilt when either changes.

use std::path::{Path, PathBuf};

use naosoccer_policy::PolicyKind;

use crate::config::TrainConfig;
use crate::env::{Opponent, VecEnv};
use crate::policy::{save_stores, self_play_snapshot, LearnedPolicy};
use crate::schedule::Schedule;
use crate::LearnError;

/// The schedule as a run plays it: the current stage, the snapshot pool,
/// and the environment's opponents rebuilt when either changes.
pub struct ScheduleRunner {
    sched: Schedule,
    stage: usize,
    /// (transitions when taken, weights file) of the kept snapshots, oldest first.
    pool: Vec<(u64, PathBuf)>,
    dir: PathBuf,
}

impl ScheduleRunner {
    /// Starts the schedule in `run_dir` (snapshots go to `run_dir/pool/`)
    /// and gives `env` the first stage's opponents. `live` are the learner's
    /// networks (the first snapshot, if the first stage needs one).
    pub fn start(
        sched: &Schedule,
        cfg: &TrainConfig,
        run_dir: &Path,
        env: &mut VecEnv,
        live: &[&tch::nn::VarStore],
    ) -> Result<ScheduleRunner, LearnError> {
        sched.validate().map_err(LearnError::Config)?;
        let dir = run_dir.join("pool");
        std::fs::create_dir_all(&dir).map_err(|e| LearnError::io(&dir, e))?;
        let mut r = ScheduleRunner {
            sched: sched.clone(),
            stage: sched.stage_at(0),
            pool: Vec::new(),
            dir,
        };
        r.snapshot(0, live)?;
        r.apply(cfg, env)?;
        Ok(r)
    }

    pub fn stage(&self) -> usize {
        self.stage
    }

    /// The runner's state for a checkpoint: its stage and its pool's
    /// snapshots (transitions, file name in `pool/`).
    pub fn state(&self) -> (usize, Vec<(u64, String)>) {
        (
            self.stage,
            self.pool
                .iter()
                .map(|(t, p)| {
                    (
                        *t,
                        p.file_name()
                            .map(|n| n.to_string_lossy().into_owned())
                            .unwrap_or_default(),
                    )
                })
                .collect(),
        )
    }

    /// A runner resumed from [`ScheduleRunner::state`]; gives `env` its
    /// stage's opponents.
    pub fn resume(
        sched: &Schedule,
        cfg: &TrainConfig,
        run_dir: &Path,
        env: &mut VecEnv,
        state: &(usize, Vec<(u64, String)>),
    ) -> Result<ScheduleRunner, LearnError> {
        let dir = run_dir.join("pool");
        let mut r = ScheduleRunner {
            sched: sched.clone(),
            stage: state.0,
            pool: state.1.iter().map(|(t, n)| (*t, dir.join(n))).collect(),
            dir,
        };
        r.apply(cfg, env)?;
        Ok(r)
    }

    fn snapshot(
        &mut self,
        transitions: u64,
        live: &[&tch::nn::VarStore],
    ) -> Result<(), LearnError> {
        let path = self.dir.join(format!("step-{transitions}.safetensors"));
        save_stores(live, &path)?;
        self.pool.push((transitions, path));
        if self.pool.len() > self.sched.pool_size {
            self.pool.remove(0);
        }
        Ok(())
    }

    /// After an update that took the run from `before` to `after`
    /// transitions: takes a snapshot when one is due and moves to the next
    /// stage when its time came; the environment's opponents are rebuilt
    /// when what they play changed.
    pub fn advance(
        &mut self,
        cfg: &TrainConfig,
        before: u64,
        after: u64,
        env: &mut VecEnv,
        live: &[&tch::nn::VarStore],
    ) -> Result<(), LearnError> {
        let every = self.sched.pool_every;
        let snap = before / every != after / every;
        if snap {
            self.snapshot(after, live)?;
        }
        let stage = self.sched.stage_at(after);
        if stage != self.stage || (snap && self.sched.uses_snapshots(stage)) {
            self.stage = stage;
            self.apply(cfg, env)?;
        }
        Ok(())
    }

    fn snapshot_policy(&self, cfg: &TrainConfig, path: &Path) -> Result<LearnedPolicy, LearnError> {
        let mut p = self_play_snapshot(cfg, None)?;
        p.load_weights(path)?;
        Ok(p)
    }

    fn apply(&mut self, cfg: &TrainConfig, env: &mut VecEnv) -> Result<(), LearnError> {
        let mut opponents = Vec::new();
        let mut weights = Vec::new();
        for (spec, w) in &self.sched.stages[self.stage].mix {
            match spec.as_str() {
                "self" => {
                    let (_, path) = self.pool.last().expect("the pool starts with a snapshot");
                    opponents.push(Opponent::Net(Box::new(self.snapshot_policy(cfg, path)?)));
                    weights.push(*w);
                }
                "pool" => {
                    let share = *w / self.pool.len() as f64;
                    for (_, path) in &self.pool {
                        opponents.push(Opponent::Net(Box::new(self.snapshot_policy(cfg, path)?)));
                        weights.push(share);
                    }
                }
                s if s.starts_with("ppo:") || s.starts_with("dqn:") => {
                    let mut p = LearnedPolicy::load(s)?;
                    p.set_match_seed(cfg.seed);
                    opponents.push(Opponent::Net(Box::new(p)));
                    weights.push(*w);
                }
                s => {
                    let kind = s
                        .parse::<PolicyKind>()
                        .map_err(|e| LearnError::Config(e.to_string()))?;
                    opponents.push(Opponent::Builtin(kind));
                    weights.push(*w);
                }
            }
        }
        env.set_opponents(opponents, &weights)
    }
}
