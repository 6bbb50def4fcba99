//! Helpers shared by the integration tests (the `integration` binary and
//! `server_logs.rs` each declare `mod common;`): running the real binary,
//! scratch files, and (in [`server`]) a real server on 127.0.0.1:0 with the
//! in-process reference match. Not every test uses every helper.
#![allow(dead_code)]

pub mod server;

use std::path::PathBuf;
use std::process::{Command, Output};

/// The real `naosoccer` binary, to be given arguments.
pub fn naosoccer_cmd() -> Command {
    Command::new(env!("CARGO_BIN_EXE_naosoccer"))
}

/// Runs `naosoccer ARGS` to its end.
pub fn naosoccer(args: &[&str]) -> Output {
    naosoccer_cmd().args(args).output().expect("run naosoccer")
}

/// What a run printed, stdout then stderr (for assertion messages).
pub fn text(out: &Output) -> String {
    format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    )
}

/// `name` in a scratch directory of its own for `test` and this process.
pub fn scratch(test: &str, name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("naosoccer-{test}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}
