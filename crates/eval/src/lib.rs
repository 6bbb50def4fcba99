//! Many matches: evaluations between two teams, leagues and the academy,
//! with their statistics, tables and JSON. Every team plays through
//! `naosoccer-policy` (built-in teams, and trained teams without libtorch),
//! every match through `referee::Match`.
//!
//! - [`eval`]: many matches between two teams; Table I with 95% CIs.
//! - [`league`]: a round robin of evaluations and a Bradley–Terry rating.
//! - [`academy`]: drills (scenarios with end conditions), many starts each,
//!   and their success rates.
//!
//! crates/learn (tch) depends on this crate for its seeds; this crate never
//! depends on it, so every command that only plays links no libtorch.

pub mod academy;
pub mod eval;
pub mod league;
