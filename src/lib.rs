//! Library side of the `naosoccer` binary: code the CLI and the end-to-end
//! tests share.
//!
//! - [`runner`]: plays a whole match in process (one `Match`, one built-in
//!   policy instance per robot) and reports the outcome.
//! - [`live`]: matches streamed to Foxglove over WebSocket (`--live`).
//! - [`interrupt`]: Ctrl-C that keeps the work done so far, and SIGPIPE.

pub mod interrupt;
pub mod live;
pub mod runner;
