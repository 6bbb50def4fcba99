//! Library side of the `naosoccer` binary: code the CLI and the end-to-end
//! tests share. Matches played in process (`match`, `bench sim`) go
//! through naosoccer-eval's one runner, `naosoccer_eval::run`.
//!
//! - [`live`]: matches streamed to Foxglove over WebSocket (`--live`).
//! - [`interrupt`]: Ctrl-C that keeps the work done so far, and SIGPIPE.

pub mod interrupt;
pub mod live;
