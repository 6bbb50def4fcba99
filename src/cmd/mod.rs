//! One module per subcommand (or family of subcommands).
pub mod animate;
pub mod bench;
pub mod client;
#[cfg(feature = "learn")]
pub mod learn;
pub mod play;
pub mod record;
pub mod server;
pub mod soak;
pub mod team;
