//! Wire types shared by the referee (which builds observations and events),
//! the server and the clients. Serde only, no IO and no physics, except
//! [`framed`] (feature `tokio`): frames over tokio streams for the server and
//! the client library.
//!
//! Everything a player sees is expressed in its team's frame: the team always
//! attacks +x, its own goal is at x = -field_length/2.
//!
//! Ids and game time are newtypes ([`Team`], [`RobotId`], [`Player`],
//! [`Tick`]) that read and write as the plain strings and numbers
//! docs/PROTOCOL.md shows; ids are validated when deserialised.

pub mod frame;
#[cfg(feature = "tokio")]
pub mod framed;
mod head;
pub mod msg;
pub mod types;

pub use types::*;
