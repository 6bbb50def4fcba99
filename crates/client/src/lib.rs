//! The robot side of naosoccer over the socket protocol: the client library
//! and the robot client loop. The policies they play (the `Policy` trait,
//! the built-in teams) live in `naosoccer_policy` and are re-exported here
//! as [`policy`].
//!
//! - [`framed`]: frames over tokio streams (`naosoccer_proto::framed`,
//!   re-exported: the server reads and writes through it too).
//! - [`net`]: [`Client`], one connection: handshake, requests, the
//!   observation/action loop over a [`Policy`].
//! - [`robot`]: one team's players as robot connections or one team connection.

pub use naosoccer_proto::framed;
pub mod net;
pub mod robot;

pub use naosoccer_policy::bots as policy;
pub use naosoccer_policy::{is_builtin_spec, ParsePolicyError, Policy, PolicyKind};
pub use net::{Client, ClientError, Played, Push};
pub use robot::{PolicyFactory, TeamPolicy};
