//! The trained teams shipped in assets/policies/ load, play, and reproduce
//! the evaluation docs/LEARNING.md reports for them (each directory keeps
//! that evaluation's output as eval.json), in the default build, which links
//! no libtorch.

use std::path::{Path, PathBuf};
use std::process::Command;

use serde_json::Value;

/// Matches of each documented evaluation replayed by default (all of them
/// with `NAOSOCCER_FULL=1`, as `scripts/test --full` sets it).
const SAMPLE: u64 = 12;

fn policies() -> Vec<PathBuf> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/policies");
    let mut dirs: Vec<PathBuf> = std::fs::read_dir(&root)
        .expect("assets/policies exists")
        .map(|e| e.unwrap().path())
        .filter(|p| p.join("final.safetensors").exists())
        .collect();
    dirs.sort();
    dirs
}

/// `ppo:DIR` or `dqn:DIR` from the directory name (`ppo-paper-seed1`, `dqn-seed2`).
fn spec(dir: &Path) -> String {
    let name = dir.file_name().unwrap().to_str().unwrap();
    let algo = name.split('-').next().unwrap();
    format!("{algo}:{}", dir.display())
}

fn eval(args: &[&str]) -> Value {
    let out = Command::new(env!("CARGO_BIN_EXE_naosoccer"))
        .arg("eval")
        .args(args)
        .arg("--json")
        .output()
        .expect("run naosoccer eval");
    assert!(
        out.status.success(),
        "eval {args:?} failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("eval --json prints one JSON object")
}

#[test]
fn every_shipped_policy_loads_and_plays() {
    let dirs = policies();
    let names: Vec<String> = dirs
        .iter()
        .map(|d| d.file_name().unwrap().to_string_lossy().into_owned())
        .collect();
    for algo in ["ppo", "dqn"] {
        let seeds = names.iter().filter(|n| n.starts_with(algo)).count();
        assert!(
            seeds >= 3,
            "{algo}: at least 3 training seeds ship, found {names:?}"
        );
    }
    for d in &dirs {
        assert!(
            d.join("eval.json").exists() && d.join("metrics.csv").exists(),
            "{} keeps its evaluation and its training curve",
            d.display()
        );
        let v = eval(&["--blue", &spec(d), "--matches", "2", "--minutes", "0.5"]);
        assert_eq!(v["scores"].as_array().unwrap().len(), 2);
    }
}

/// The documented evaluation (50 ten-minute matches against the scripted
/// team; 100 on both sides for the `team` presets) played again through the
/// torch-free forward pass (`naosoccer-policy`, what the default build
/// plays with): every match comes out as documented, score for score. The
/// evaluations were made through tch; the plain-Rust forward pass agrees
/// with it closely enough that no draw and no greedy choice changes
/// (issue 14), and it does not depend on the CPU or the batch.
///
/// By default the first [`SAMPLE`] matches of each evaluation are played
/// (a block, as `eval --first-match` plays it) and each must equal its
/// documented match; with `NAOSOCCER_FULL=1` (`scripts/test --full`) every
/// match is, and so are the reports' means and tallies.
#[test]
fn shipped_policies_reproduce_their_documented_evaluation() {
    let full = std::env::var("NAOSOCCER_FULL").is_ok_and(|v| v == "1");
    for d in policies().iter().filter(|d| {
        [
            "ppo-paper-seed1",
            "dqn-seed1",
            "ppo-team-seed1",
            "dqn-team-seed1",
        ]
        .iter()
        .any(|name| d.ends_with(name))
    }) {
        let doc: Value =
            serde_json::from_str(&std::fs::read_to_string(d.join("eval.json")).unwrap()).unwrap();
        let all = doc["matches"].as_u64().unwrap();
        let played = if full { all } else { all.min(SAMPLE) };
        let matches = played.to_string();
        let seed = doc["seed"].as_u64().unwrap().to_string();
        let minutes = doc["minutes"].as_f64().unwrap().to_string();
        let red = doc["red"]["name"].as_str().unwrap();
        let blue = spec(d);
        let mut args = vec![
            "--blue",
            &blue,
            "--red",
            red,
            "--matches",
            &matches,
            "--seed",
            &seed,
            "--minutes",
            &minutes,
        ];
        // Evaluations made before evaluation seeds had their own derivation
        // do not name a scheme.
        if doc["seed_scheme"].as_str().is_none_or(|s| s == "legacy") {
            args.push("--legacy-seeds");
        }
        if doc["both_sides"] == true {
            args.push("--both-sides");
        }
        let got = eval(&args);
        let differ: Vec<usize> = (0..played as usize)
            .filter(|&i| {
                got["scores"][i] != doc["scores"][i]
                    || ["control_rate_percent", "passes", "shots", "state_hash"]
                        .iter()
                        .any(|k| got["results"][i][k] != doc["results"][i][k])
            })
            .collect();
        assert!(
            differ.is_empty(),
            "{}: matches {differ:?} differ from the documented evaluation",
            d.display()
        );
        if !full {
            continue;
        }
        for team in ["blue", "red"] {
            for figure in ["goals", "control_rate_percent", "passes", "shots"] {
                assert_eq!(
                    got[team][figure]["mean"],
                    doc[team][figure]["mean"],
                    "{}: {team} {figure}",
                    d.display()
                );
            }
            for tally in ["wins", "draws", "losses"] {
                assert_eq!(
                    got[team][tally],
                    doc[team][tally],
                    "{}: {team} {tally}",
                    d.display()
                );
            }
        }
    }
}
