//! Wire types shared by the referee (which builds observations and events),
//! the server and the clients. Serde only: no IO, no physics.
//!
//! Everything a player sees is expressed in its team's frame: the team always
//! attacks +x, its own goal is at x = -field_length/2.

pub mod frame;
pub mod msg;
pub mod types;

pub use types::*;
