//! `naosoccer eval` in blocks (`--first-match`) and merged again
//! (`--merge`), through the real binary: the merge of the blocks prints what
//! one run over all their matches prints, and files of other evaluations,
//! overlaps and gaps are refused.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::sync::atomic::{AtomicUsize, Ordering};

use serde_json::Value;

fn naosoccer(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_naosoccer"))
        .args(args)
        .output()
        .expect("run naosoccer")
}

fn dir(name: &str) -> PathBuf {
    let d = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(name);
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn stdout(out: Output, what: &str) -> String {
    assert!(
        out.status.success(),
        "{what} failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout).unwrap()
}

/// The evaluation under test: scripted v random, 6 matches of 0.3 minutes.
fn eval_args(extra: &[&str]) -> Vec<String> {
    let mut args: Vec<String> = [
        "eval",
        "--blue",
        "scripted",
        "--red",
        "random",
        "--seed",
        "21",
        "--minutes",
        "0.3",
    ]
    .map(String::from)
    .to_vec();
    args.extend(extra.iter().map(|s| s.to_string()));
    args
}

fn eval(extra: &[&str]) -> String {
    let args = eval_args(extra);
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    stdout(naosoccer(&args), &format!("{args:?}"))
}

/// Plays matches `first .. first + matches - 1` and writes the --json to a file.
fn block(d: &Path, first: usize, matches: usize, extra: &[&str]) -> String {
    let (f, m) = (first.to_string(), matches.to_string());
    let mut args = vec!["--first-match", &f, "--matches", &m, "--json"];
    args.extend_from_slice(extra);
    let text = eval(&args);
    // Numbered: blocks of the same matches from other evaluations must not
    // overwrite each other.
    static FILES: AtomicUsize = AtomicUsize::new(0);
    let n = FILES.fetch_add(1, Ordering::Relaxed);
    let path = d.join(format!("block-{n}-{first}-{matches}.json"));
    std::fs::write(&path, &text).unwrap();
    path.to_str().unwrap().to_string()
}

fn json(text: &str) -> Value {
    serde_json::from_str(text).expect("one JSON object")
}

fn without_wall(mut v: Value) -> Value {
    v.as_object_mut().unwrap().remove("wall_seconds");
    v
}

fn merge(files: &[&str], extra: &[&str]) -> Output {
    let mut args = vec!["eval", "--merge"];
    args.extend_from_slice(files);
    args.extend_from_slice(extra);
    naosoccer(&args)
}

fn merged_equals_one_run(both_sides: bool) {
    let d = dir(&format!("eval_blocks_{both_sides}"));
    let sides: &[&str] = if both_sides { &["--both-sides"] } else { &[] };
    let whole_text = eval(&[&["--matches", "6", "--json"][..], sides].concat());
    let whole = json(&whole_text);
    let files = [(5, 1), (0, 2), (2, 3)].map(|(first, n)| block(&d, first, n, sides));
    let files: Vec<&str> = files.iter().map(String::as_str).collect();

    let got = json(&stdout(merge(&files, &["--json"]), "merge --json"));
    assert_eq!(without_wall(got.clone()), without_wall(whole.clone()));
    // The fields the blocks brought: every match, by its global index.
    assert_eq!(whole["first_match"], 0);
    let results = whole["results"].as_array().unwrap();
    assert_eq!(results.len(), 6);
    for (i, r) in results.iter().enumerate() {
        assert_eq!(r["index"], i);
        assert_eq!(r["swapped"], whole["swapped"][i]);
        assert_eq!(r["goals"], whole["scores"][i]);
        assert_eq!(r["swapped"], both_sides && i % 2 == 1);
    }
    // A block is the slice of the whole run, first_match and all.
    let b = json(&std::fs::read_to_string(files[2]).unwrap());
    assert_eq!(b["first_match"], 2);
    assert_eq!(b["matches"], 3);
    assert_eq!(b["results"].as_array().unwrap()[..], results[2..5]);
    assert_eq!(
        b["scores"].as_array().unwrap()[..],
        whole["scores"].as_array().unwrap()[2..5]
    );
    // The merged wall time is the sum of the blocks'.
    let sum: f64 = files
        .iter()
        .map(|f| {
            json(&std::fs::read_to_string(f).unwrap())["wall_seconds"]
                .as_f64()
                .unwrap()
        })
        .sum();
    assert!((got["wall_seconds"].as_f64().unwrap() - sum).abs() < 1e-9);

    // The table too, but for the wall-clock time on its last line.
    let table = stdout(merge(&files, &[]), "merge");
    let one_run = eval(&[&["--matches", "6"][..], sides].concat());
    let body = |t: &str| t.lines().map(str::to_string).collect::<Vec<_>>();
    let (got_lines, want_lines) = (body(&table), body(&one_run));
    assert_eq!(got_lines.len(), want_lines.len());
    assert_eq!(
        got_lines[..got_lines.len() - 1],
        want_lines[..want_lines.len() - 1]
    );
    assert!(table.starts_with("6 matches"));
    assert_eq!(table.contains("half with the sides swapped"), both_sides);

    // Blocks 2..6 alone are the run of --first-match 2 --matches 4.
    let tail = json(&stdout(
        merge(&[files[2], files[0]], &["--json"]),
        "merge tail",
    ));
    let want = json(&eval(
        &[
            &["--first-match", "2", "--matches", "4", "--json"][..],
            sides,
        ]
        .concat(),
    ));
    assert_eq!(without_wall(tail), without_wall(want));
}

#[test]
fn merged_blocks_equal_one_run() {
    merged_equals_one_run(false);
}

#[test]
fn merged_blocks_equal_one_run_with_both_sides() {
    merged_equals_one_run(true);
}

fn refused(out: Output, needle: &str) {
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success(),
        "accepted; stdout: {}",
        String::from_utf8_lossy(&out.stdout)
    );
    assert!(err.contains(needle), "expected {needle:?} in: {err}");
}

#[test]
fn merge_refuses_other_evaluations_overlaps_and_gaps() {
    let d = dir("eval_blocks_refused");
    let a = block(&d, 0, 2, &[]);
    let b = block(&d, 2, 1, &[]);
    let sides = block(&d, 2, 1, &["--both-sides"]);
    refused(merge(&[&a, &sides], &[]), "both_sides is true there");
    let legacy = block(&d, 2, 1, &["--legacy-seeds"]);
    refused(merge(&[&a, &legacy], &[]), "seed_scheme is legacy there");
    let config = d.join("standup.toml");
    std::fs::write(&config, "[rules]\nstandup_seconds = 4.0\n").unwrap();
    let other_config = block(&d, 2, 1, &["--config", config.to_str().unwrap()]);
    refused(merge(&[&a, &other_config], &[]), "config_hash is");
    // Another team, seed or match length: match 2 of another evaluation.
    for (red, seed, minutes, needle) in [
        ("idle", "21", "0.3", "--red is idle there"),
        ("random", "22", "0.3", "seed is 22 there"),
        ("random", "21", "0.35", "minutes is 0.35 there"),
    ] {
        let out = naosoccer(&[
            "eval",
            "--blue",
            "scripted",
            "--red",
            red,
            "--seed",
            seed,
            "--minutes",
            minutes,
            "--matches",
            "1",
            "--first-match",
            "2",
            "--json",
        ]);
        let other = d.join(format!("other-{red}-{seed}-{minutes}.json"));
        std::fs::write(&other, stdout(out, needle)).unwrap();
        refused(merge(&[&a, other.to_str().unwrap()], &[]), needle);
    }

    // Overlaps and gaps.
    let middle = block(&d, 1, 2, &[]);
    refused(merge(&[&a, &middle], &[]), "match 1 is in both");
    refused(merge(&[&a, &a], &[]), "match 0 is in both");
    let late = block(&d, 4, 1, &[]);
    refused(merge(&[&a, &late, &b], &[]), "match 3 is missing");
    refused(merge(&[&late, &a], &[]), "matches 2 to 3 are missing");
    // The good set still merges.
    stdout(merge(&[&b, &a], &["--json"]), "merge a b");

    // Not an eval --json with per-match results: a table, an old file.
    let table = d.join("table.txt");
    std::fs::write(&table, eval(&["--matches", "1"])).unwrap();
    refused(merge(&[&a, table.to_str().unwrap()], &[]), "not JSON");
    let mut old = json(&std::fs::read_to_string(&b).unwrap());
    old.as_object_mut().unwrap().remove("results");
    let old_file = d.join("old.json");
    std::fs::write(&old_file, old.to_string()).unwrap();
    refused(
        merge(&[&a, old_file.to_str().unwrap()], &[]),
        "no per-match \"results\"",
    );
    // A record edited to another match.
    let mut edited = json(&std::fs::read_to_string(&b).unwrap());
    edited["results"][0]["index"] = 7.into();
    let edited_file = d.join("edited.json");
    std::fs::write(&edited_file, edited.to_string()).unwrap();
    refused(
        merge(&[&a, edited_file.to_str().unwrap()], &[]),
        "is not match 2 of the plan",
    );

    // --merge plays nothing: the options of a run are refused with it.
    refused(
        naosoccer(&["eval", "--merge", &a, "--blue", "scripted"]),
        "cannot be used with",
    );
    refused(
        naosoccer(&["eval", "--merge", &a, "--matches", "3"]),
        "cannot be used with",
    );
    refused(naosoccer(&["eval", "--matches", "3"]), "--blue");
    refused(
        naosoccer(&["eval", "--merge", d.join("absent.json").to_str().unwrap()]),
        "absent.json",
    );
}
