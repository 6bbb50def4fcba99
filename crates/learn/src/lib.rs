//! Learning: team policies for `referee::Match`, trained with PPO and DQN
//! on tch. The only crate that links libtorch; playing a trained team needs
//! only `naosoccer-policy` (re-exported here as [`obs`] and the
//! [`LearnedPolicy`] the trainer's opponents use), and evaluating one only
//! `naosoccer-eval` (re-exported as [`eval`]). The reward is the
//! referee's (`Match::rewards`): its weights are part of the match
//! configuration.
//!
//! Three parts, and where a change goes.
//!
//! **The environment**: what a learner sees and does.
//! - [`mod@env`]: many matches in process, stepped together; the learning
//!   team's robots as one batch of rows; built-in, frozen, self-play or
//!   mixed opponents; drills. Each match is a `naosoccer_eval::run::MatchSlot`,
//!   stepped as evaluations and the CLI step theirs.
//! - [`env::decisions`]: the decision-level MDP over the matches, and the
//!   only place that holds actions and keeps decisions open: who decides
//!   this tick, under which masks; each closed decision comes out as one
//!   transition (observation, action, discounted reward, discount, how it
//!   ended).
//! - [`obs`]: the observation vector (versioned layout, see
//!   docs/LEARNING.md).
//!
//! **The run harness**: what a run needs that is not the algorithm.
//! - [`mod@train`]: the front door: the learner a configuration asks for;
//!   resume.
//! - [`run`]: the run directory, metrics rows, checkpoints, self-play
//!   snapshots and the opponent schedule as played (its `Run`); the
//!   environment built from a configuration ([`run::setup`]); resumable
//!   checkpoints ([`run::resume`]).
//! - [`metrics`]: the rows of `metrics.csv` and the tally behind them.
//! - [`config`]: a run's configuration (its `config.json`); [`schedule`]
//!   and [`schedule_runner`]: opponent curricula; [`warm_start`]: a PPO
//!   run that starts from a trained team.
//!
//! **The learners**: one file each, read top to bottom: the loop, acting,
//! storing, updating; each runs every preset of its algorithm on
//! [`env::decisions`] (robots deciding when free to act, or every robot
//! every tick).
//! - [`ppo`]: PPO: for a team on the decision-level MDP (`--preset
//!   team`), and with every robot acting every tick (the paper's Algorithm
//!   2, `paper`; CleanRL's `ppo.py`, `cleanrl`); what it stores,
//!   decision-level transitions and their estimators (GAE, the paper's
//!   returns), is [`rollout`].
//! - [`dqn`]: DQN: the paper's Algorithm 1, every robot acting every
//!   tick (`paper`), and on the decision-level MDP (`--preset team`); what
//!   it stores, n-step returns and the replay ring, is [`replay`].
//! - What they share: [`nets`] (the networks, value normalisation) and
//!   [`adam`] (an Adam whose state a checkpoint saves).
//!
//! A third algorithm is one new file beside these: a `train` that builds
//! the environment (`run::make_env`), acts on [`env::decisions::Decisions`],
//! stores and updates, and drives a `run::Run` for everything else; its
//! settings join [`config`] (an [`Algo`] variant) and one line of
//! [`train::train`] sends its runs to it.
//!
//! Around them: [`policy`], the trainer's networks as players (self-play
//! snapshots, frozen opponents); [`eval`], many matches between two teams;
//! [`plot`], training curves (Figures 4-6).

pub mod adam;
pub mod config;
pub mod dqn;
pub mod env;
mod error;
pub mod metrics;
pub mod nets;
pub mod plot;
pub mod policy;
pub mod ppo;
pub mod replay;
pub mod rollout;
pub mod run;
pub mod schedule;
pub mod schedule_runner;
pub mod train;
pub mod warm_start;

pub use config::{Algo, OpponentSpec, TrainConfig};
pub use error::LearnError;
pub use naosoccer_eval::eval;
pub use naosoccer_policy::obs;
pub use naosoccer_policy::{load_policy, load_policy_for_match, ActMode, LearnedPolicy};
pub use obs::{ObsScale, OBS_DIM, OBS_VERSION, OBS_VERSION_LATEST};
pub use train::train;
