//! The front door: a run's configuration in, the learner that trains it
//! out. Each learner is one file with its loop ([`crate::ppo`],
//! [`crate::dqn`]), runs every preset of its algorithm and drives the run
//! harness ([`crate::run`]).

use std::path::Path;

use crate::metrics::Progress;
use crate::run::resume::resume_point;
use crate::run::TrainSummary;
use crate::{dqn, ppo, LearnError};

// The configuration and the self-play snapshot live where the modules that
// read them can reach them without importing the learners; these are their
// historical paths.
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
        // Each on the decision-level MDP: robots deciding when free to act
        // (`--preset team`), or every robot every tick (the paper's
        // presets, and PPO's `cleanrl`).
        Algo::Ppo => ppo::train(cfg, out, None, progress),
        Algo::Dqn => dqn::train(cfg, out, progress),
    }
}

/// Continues the run in `dir` from its latest resumable checkpoint, as if
/// it had not stopped (team-preset PPO runs; `steps`, if given, replaces
/// the run's length, `threads` the threads stepping its matches, which
/// changes nothing it learns). metrics.csv keeps the rows up to that
/// checkpoint.
pub fn resume(
    dir: &Path,
    steps: Option<u64>,
    threads: Option<usize>,
    progress: &mut dyn FnMut(&Progress<'_>),
) -> Result<TrainSummary, LearnError> {
    let (cfg, state) = resume_point(dir, steps, threads)?;
    tch::manual_seed(cfg.seed as i64);
    ppo::train(&cfg, dir, Some(state), progress)
}
