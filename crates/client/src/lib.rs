//! The robot side of naosoccer: the `Policy` trait, the built-in policies
//! (scripted, random, idle) and, over the socket protocol, the client library
//! and the robot client loop.
//!
//! - [`framed`]: frames over tokio streams (`naosoccer_proto::framed`,
//!   re-exported: the server reads and writes through it too).
//! - [`net`]: [`Client`], one connection: handshake, requests, the
//!   observation/action loop over a [`Policy`].
//! - [`robot`]: one team's players as robot connections or one team connection.

pub use naosoccer_proto::framed;
pub mod net;
pub mod policy;
pub mod robot;

pub use net::{Client, ClientError, Played, Push};
pub use policy::{is_builtin_spec, ParsePolicyError, Policy, PolicyKind};
pub use robot::{PolicyFactory, TeamPolicy};
