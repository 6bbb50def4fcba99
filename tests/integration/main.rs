//! The integration tests, one module per area, in one test binary (as
//! ripgrep's are): one link instead of one per file, and the helpers in
//! `tests/common` compiled once. Run a part with a filter, for example
//! `cargo test --test integration server_errors::`.
//!
//! `tests/server_logs.rs` stays a binary of its own: it captures the logs
//! with a process-wide subscriber, which would see every test here.

#[path = "../common/mod.rs"]
mod common;

mod academy_cli;
mod eval_blocks;
mod interrupt_cli;
mod league_cli;
mod learn_cli;
mod learn_client;
// Pinned training bytes (issue 41): the runs need libtorch.
#[cfg(feature = "train")]
mod learn_pins;
mod learn_shipped;
mod live;
mod match_cli;
mod match_football;
mod physics_plausibility;
mod protocol_1_1_client;
mod protocol_docs;
mod record_cli;
mod record_server;
mod render_gif;
mod server_e2e;
mod server_errors;
mod server_hardening;
mod server_hardening_props;
mod server_protocol_1_2;
mod server_protocol_1_5;
mod server_protocol_1_6;
