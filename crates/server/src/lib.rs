//! The match server: listener, connections, lockstep and real-time
//! schedulers, many matches at once.
//!
//! Layout (after tokio-rs/mini-redis):
//! - [`run`] / [`run_with`] (`server`): accept loop, connection limits,
//!   graceful shutdown (a future passed in; the server waits until every
//!   task is done).
//! - `shared`: what every connection shares; the match registry.
//! - `handler`: one task per client connection, its read loop and deadlines.
//! - `connection`: frames in and out (`naosoccer_proto::framed`), nothing else.
//! - `session`: one client's state (greeting, seat in a match, rate bucket).
//! - `cmd`: one handler per request kind.
//! - `limits`: the byte-counting reader and the message-rate bucket.
//! - `match_task`: one task per match owns its `referee::Match`; joins,
//!   leaves and actions arrive over a channel (`match_msg`), observations
//!   leave over one per connection.
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

mod cmd;
pub mod config;
mod connection;
mod handler;
mod limits;
mod match_msg;
mod match_task;
pub mod observer;
pub mod recording;
mod server;
mod session;
mod shared;

pub use config::Limits;
pub use config::{ConfigError, ServerConfig, TokenConfig, Tokens};
pub use observer::{FillFactory, FillTeam, Hooks, MatchObserver, TickRecord};
pub use server::{run, run_with, ServerError};
