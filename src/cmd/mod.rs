//! One module per subcommand (or family of subcommands).
pub mod bench;
pub mod client;
pub mod play;
pub mod server;
