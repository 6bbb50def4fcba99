//! Issue 41, item 5: the bytes a training run writes, pinned. Two short runs
//! of the shipped `team` recipes go through the real binary, and the
//! SHA-256 of their `metrics.csv` and `final.safetensors` must be the ones
//! recorded here.
//!
//! What the pins protect: the learning code's behaviour, bit for bit, while
//! it is moved around (environment, run harness and algorithms apart). Each
//! run takes the paths a shipped team took: PPO's decision-level loop with
//! warm-start weight surgery (`--init-from` a five-action team, gaining
//! `pass` and `support`), pass drills cut and bootstrapped, an opponent
//! schedule with its snapshot pool, episode ends, checkpoints with resume
//! state; DQN's decision-level loop with n-step returns, its replay past
//! warm-up, gradient steps, episode ends and checkpoints. A refactoring
//! that keeps the bytes keeps these pins; one that changes them changed
//! what training does.
//!
//! The commands are the shipped ones of docs/LEARNING.md ("The `team`
//! presets: shipped teams") with test-sized lengths:
//! - PPO (the facing recipe): 200k transitions instead of 10M, and 2-minute
//!   episodes instead of 10, so that episodes end within the run and
//!   checkpoints (written at episode boundaries) are taken; it starts from
//!   `ppo-team-v3-seed1`, as the shipped `ppo-team-seed1` did.
//! - DQN: 160k transitions instead of 6M. Not 60k: the team preset's replay
//!   learns from 20,000 decisions on, which a run reaches after about 60k
//!   transitions, and its 2-minute episodes end after 77k; a 60k run would
//!   pin untrained weights and no episode's end.
//!
//! Both run with `--threads 1` and the test profile's binary; a release
//! build writes the same bytes. The bytes depend on libtorch's version and
//! on the CPU's kernels (they were recorded on x86-64 with AVX-512, libtorch
//! 2.13 from scripts/setup): on another kind of machine these pins may fail
//! while nothing in the code changed, so check there against a run of the
//! unchanged code before blaming a change.
//!
//! When a change is meant to change training (a fix, a new default), run
//! the test, check that only the runs it should affect differ, and replace
//! the hashes with the ones the failure message prints, saying in the
//! commit why the bytes moved. Run it alone with
//! `cargo test --features train --test integration learn_pins::`.

use crate::common;

use std::path::{Path, PathBuf};

use sha2::{Digest, Sha256};

/// The shipped PPO facing recipe, test-sized (see the module's comment).
const PPO_TEAM: &[&str] = &[
    "train",
    "--algo",
    "ppo",
    "--preset",
    "team",
    "--config",
    "assets/train-team-facing.toml",
    "--obs-version",
    "3",
    "--minutes",
    "2",
    "--opponent",
    "schedule:scripted+scripted:assets/scripted/hound.toml+pool=2",
    "--pass-drills",
    "4",
    "--pass-action",
    "--support-action",
    "--support-hold",
    "60",
    "--support-roles",
    "2",
    "--support-spot",
    "facing",
    "--init-from",
    "assets/policies/ppo-team-v3-seed1",
    "--pass-init",
    "turn_left",
    "--support-init-bias",
    "0",
    "--lr",
    "0.0001",
    "--entropy-coef",
    "0.006",
    "--steps",
    "200000",
    "--seed",
    "1",
    "--threads",
    "1",
    "--checkpoint-every",
    "50000",
];

const PPO_TEAM_METRICS: &str = "db34f43371167e88427593d7cfc6c06fe3f9d840525dc5995c654b961b4d6285";
const PPO_TEAM_FINAL: &str = "670278f4926466e8535cf5e8ded1ee2540f7fe281702819c265c9c799a05d4dd";

/// The shipped DQN team recipe, test-sized (see the module's comment).
const DQN_TEAM: &[&str] = &[
    "train",
    "--algo",
    "dqn",
    "--preset",
    "team",
    "--opponent",
    "random",
    "--config",
    "assets/train-dqn-team.toml",
    "--minutes",
    "2",
    "--steps",
    "160000",
    "--seed",
    "1",
    "--threads",
    "1",
    "--checkpoint-every",
    "50000",
];

const DQN_TEAM_METRICS: &str = "abfc12ef0141ad1f3e53351a57199a88325c15627897f41129c146445eafd86b";
const DQN_TEAM_FINAL: &str = "902cb316aaad14a404e9fafa2a8f0aa356144cbff76fe6b5167be6e8969e9cc2";

fn sha256(path: &Path) -> String {
    let bytes = std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    Sha256::digest(&bytes)
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect()
}

/// Runs `args --out DIR` from the repository's root (the paths in the
/// commands are the documentation's), checks that it wrote `checkpoint`
/// and the two files' hashes.
fn run_and_check(name: &str, args: &[&str], checkpoint: &str, metrics: &str, weights: &str) {
    let out = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(name);
    let _ = std::fs::remove_dir_all(&out);
    let run = common::naosoccer_cmd()
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .args(args)
        .arg("--out")
        .arg(&out)
        .output()
        .expect("run naosoccer train");
    assert!(run.status.success(), "{}", common::text(&run));
    // The checkpoint code ran (its files are not pinned: the run's end is).
    assert!(
        out.join(checkpoint).exists(),
        "{name}: {checkpoint} written"
    );
    let got = (
        sha256(&out.join("metrics.csv")),
        sha256(&out.join("final.safetensors")),
    );
    assert_eq!(
        (got.0.as_str(), got.1.as_str()),
        (metrics, weights),
        "{name}: training wrote other bytes than the pinned ones (metrics.csv, \
         final.safetensors). If the change is meant to change training, replace \
         the pins with these and say why in the commit: metrics {}, final {}\n\
         command: naosoccer {} --out {}",
        got.0,
        got.1,
        args.join(" "),
        out.display()
    );
}

#[test]
fn issue_41_the_ppo_team_recipe_writes_the_pinned_bytes() {
    run_and_check(
        "pin_ppo_team",
        PPO_TEAM,
        "checkpoints/step-76800.resume.json",
        PPO_TEAM_METRICS,
        PPO_TEAM_FINAL,
    );
}

#[test]
fn issue_41_the_dqn_team_recipe_writes_the_pinned_bytes() {
    run_and_check(
        "pin_dqn_team",
        DQN_TEAM,
        "checkpoints/step-50048.safetensors",
        DQN_TEAM_METRICS,
        DQN_TEAM_FINAL,
    );
}
