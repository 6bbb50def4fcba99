//! The match server: listener, connections, lockstep and real-time
//! schedulers, many matches at once.
//!
//! Layout (after tokio-rs/mini-redis):
//! - [`run`] / [`run_with`]: accept loop, connection limit, graceful shutdown
//!   (a future passed in; the server waits until every task is done).
//! - `connection`: one task per client; frames (via
//!   `naosoccer_client::framed`), requests and replies, in order.
//! - `match_task`: one task per match owns its `referee::Match`; joins,
//!   leaves and actions arrive over a channel, observations leave over one
//!   per connection.
//! - [`observer`]: the per-match hook a recorder plugs into.
//!
//! The wire protocol is in `naosoccer_proto::msg` and docs/PROTOCOL.md.
//!
//! `Match::step` runs on the match task itself, not in `spawn_blocking`: a
//! whole control tick (10 physics steps, rules, observations) costs about
//! 0.1 ms in a release build (`bench server` prints the in-process rate), so
//! it never holds a worker long, while a blocking-pool hand-off costs about
//! 27 us a round trip on the 2-core machine we measured: a quarter of the
//! tick again, for every tick of every match.

pub mod config;
mod connection;
mod match_task;
pub mod observer;
pub mod recording;
mod server;

pub use config::Limits;
pub use config::{ConfigError, ServerConfig, TokenConfig, Tokens};
pub use observer::{Hooks, MatchObserver, TickRecord};
pub use server::{run, run_with, ServerError};
