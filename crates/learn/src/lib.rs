//! Learning: the MDP over `referee::Match`, DQN and PPO on tch. The only
//! crate that links libtorch; playing a trained team needs only
//! `naosoccer-policy` (re-exported here as [`obs`], [`eval`] and the
//! [`LearnedPolicy`] the trainer's opponents use).
//!
//! - [`obs`]: the observation vector (versioned layout, see docs/LEARNING.md).
//! - [`env`]: many matches in process, stepped together; the learning team's
//!   robots flattened into one batch; built-in, frozen or self-play opponents.
//! - [`ppo`], [`dqn`]: the two algorithms as the paper describes them (PPO
//!   also with a CleanRL preset).
//! - [`config`]: a training run's configuration (its `config.json`).
//! - [`schedule`]: opponent curricula, as written on the command line.
//! - [`schedule_runner`]: a schedule played: its stages and the pool of past
//!   snapshots.
//! - [`train`]: training runs (metrics CSV, safetensors checkpoints, resume).
//! - [`policy`]: the trainer's networks as players (self-play snapshots,
//!   frozen opponents), through `naosoccer-policy`'s forward pass.
//! - [`eval`]: many matches between two teams; Table I with 95% CIs.
//! - [`plot`]: training curves (Figures 4-6).
//!
//! The reward is the referee's (`Match::rewards`): its weights are part of the
//! match configuration.

pub mod adam;
pub mod config;
pub mod decisions;
pub mod dqn;
pub mod env;
mod error;
pub mod nets;
pub mod plot;
pub mod policy;
pub mod ppo;
pub mod run;
pub mod schedule;
pub mod schedule_runner;
pub mod train;
pub mod warm_start;

pub use config::{Algo, OpponentSpec, TrainConfig};
pub use error::LearnError;
pub use naosoccer_policy::{eval, obs};
pub use naosoccer_policy::{load_policy, load_policy_for_match, ActMode, LearnedPolicy};
pub use obs::{ObsScale, OBS_DIM, OBS_VERSION, OBS_VERSION_LATEST};
pub use train::train;
