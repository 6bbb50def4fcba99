//! One module per subcommand (or family of subcommands).
pub mod bench;
pub mod client;
pub mod eval;
pub mod league;
#[cfg(feature = "train")]
pub mod learn;
#[cfg(not(feature = "train"))]
pub mod not_built;
pub mod play;
pub mod record;
pub mod server;
pub mod soak;
pub mod team;
