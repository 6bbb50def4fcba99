//! Many matches: evaluations between two teams, leagues and the academy,
//! with their statistics, tables and JSON. Every team plays through
//! `naosoccer-policy` (built-in teams, and trained teams without libtorch),
//! every match through `referee::Match`.
//!
//! - [`run`]: the one runner of batches of matches: seeds, sides and
//!   scenarios in, each match stepped to its end (threads, one forward pass
//!   a tick for a trained team), per-match results out; one match alone,
//!   watched tick by tick (the CLI's `match`). Its [`run::MatchSlot`] (a
//!   match, its built-in robots, observations, actions and a scenario's
//!   judge, stepped one way) is also what the learning crate's vectorised
//!   environment and the Python package's vector env step.
//! - [`eval`]: many matches between two teams; Table I with 95% CIs.
//!   - `eval/seeds.rs`: evaluation and training seeds.
//!   - `eval/stats.rs`: means with Student-t intervals, Wilson rates, a
//!     team's row.
//!   - `eval/table.rs`, `eval/report.rs`: the table; the report, its JSON,
//!     reading back and merging blocks.
//! - [`league`]: a round robin of evaluations and a Bradley–Terry rating.
//! - [`academy`]: drills (scenarios with end conditions), many starts each,
//!   and their success rates.
//!
//! crates/learn (tch) depends on this crate for its seeds; this crate never
//! depends on it, so every command that only plays links no libtorch.

pub mod academy;
pub mod eval;
pub mod league;
pub mod run;
