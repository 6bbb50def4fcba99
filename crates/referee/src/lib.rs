//! Rules over sim state and [`Match`], the one driver used by the server, the
//! in-process runner and training alike.
//!
//! - [`rules`]: one type per rule (clock, kick-off, goal, out of bounds, fall,
//!   possession, pass), each a function of a sim snapshot and the tick that
//!   returns events and commands; rules never touch the sim.
//! - [`Match`]: maps the eight robots' actions to sim commands, steps physics
//!   for one control tick, runs the rules, applies their commands, keeps the
//!   score and statistics (derived from the event stream) and builds each
//!   player's observation, mirrored so every team attacks +x.
//! - [`MatchConfig`]: the whole match in one TOML file (`assets/match.toml`).
//!
//! API CONTRACT (used by server, learn, the CLI; keep these signatures):
//! ```ignore
//! pub struct MatchConfig { pub sim: SimConfig, pub rules: RulesConfig, pub reward: RewardConfig, pub minutes: f32, pub control_hz: f32, .. }
//!     // serde + Default (paper values) ; MatchConfig::from_toml_str(&str) / from_file(&Path) -> Result<_, ConfigError>;
//!     // MatchConfig::default() equals assets/match.toml
//! pub struct Match { .. }
//! impl Match {
//!     pub fn new(cfg: &MatchConfig, seed: u64) -> Result<Match, MatchError>;
//!     pub fn step(&mut self, actions: &[proto::Action; 8]) -> &[proto::Event]; // one control tick: events of that tick
//!     pub fn observe(&self, team: Team, player: usize) -> proto::Observation;   // mirrored: team attacks +x
//!     pub fn observe_into(&self, team: Team, player: usize, out: &mut proto::Observation);
//!     pub fn tick(&self) -> u64;  pub fn total_ticks(&self) -> u64;  pub fn is_finished(&self) -> bool;
//!     pub fn score(&self) -> (u32, u32); pub fn stats(&self) -> proto::MatchStats;
//!     pub fn state_hash(&self) -> u64; pub fn seed(&self) -> u64; pub fn config(&self) -> &MatchConfig;
//!     pub fn sim(&self) -> &Sim; pub fn sim_mut(&mut self) -> &mut Sim;  // tests stage situations
//!     pub fn controller(&self) -> Option<RobotId>;  // who holds the ball (if_c), at most one
//!     pub fn rewards(&self, team: Team) -> [f32; 4]; // per-robot reward of the last tick (learn's MDP)
//! }
//! ```
//! Also: `Match::sim_seconds`, `steps_per_tick`, `field`, `is_down`, `up_at`;
//! `MatchConfig::validate` / `to_toml_string`; `blank_observation()`;
//! `log_compress`.

pub mod config;
mod game;
mod observe;
pub mod rules;
mod sim_glue;

pub use config::{ConfigError, FirstKickOff, MatchConfig, Placement, RewardConfig, RulesConfig};
pub use game::{log_compress, Match, MatchError};
pub use observe::blank_observation;
pub use rules::{Command, Field};

/// The default configuration file, as shipped (`assets/match.toml`).
pub const DEFAULT_CONFIG_TOML: &str = include_str!("../../../assets/match.toml");
