//! Rules over sim state and [`Match`], the one driver used by the server, the
//! in-process runner and training alike.
//!
//! - [`rules`]: one type per rule (clock, kick-off, goal, out of bounds, fall,
//!   possession, pass, set play), each a function of a sim snapshot and the
//!   [`Tick`](naosoccer_proto::Tick) that returns events and commands; rules
//!   never touch the sim.
//! - [`Match`]: maps the eight robots' actions to sim commands, steps physics
//!   for one control tick, runs the rules, applies their commands, keeps the
//!   score and statistics (derived from the event stream) and builds each
//!   player's observation, mirrored so every team attacks +x.
//! - [`MatchConfig`]: the whole match in one TOML file (`assets/match.toml`).
//! - [`Scenario`]: a match started from a documented state, and the judge
//!   of its end conditions (docs/SCENARIOS.md).

pub mod config;
mod game;
mod observe;
pub mod rules;
pub mod scenario;
mod sim_glue;

pub use config::{ConfigError, FirstKickOff, MatchConfig, Placement, RewardConfig, RulesConfig};
pub use game::{log_compress, Match, MatchError, StateError, MAX_BALL_SPEED};
pub use observe::blank_observation;
pub use rules::{Command, Field};
pub use scenario::{Ending, Judge, RobotStart, Scenario, ScenarioError};

/// The default configuration file, as shipped (`assets/match.toml`).
pub const DEFAULT_CONFIG_TOML: &str = include_str!("../../../assets/match.toml");
