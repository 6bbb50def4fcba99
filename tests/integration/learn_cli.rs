//! The learning subcommands end to end through the real binary: a short
//! training run, an evaluation of what it wrote, a plot of its metrics, and
//! clear errors on bad input (with the `train` feature); evaluation and
//! trained teams in matches (in every build); and, in a build without
//! training, what `train` says to run.

use crate::common;

use common::naosoccer;

use std::path::PathBuf;

fn dir(name: &str) -> PathBuf {
    let d = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(name);
    let _ = std::fs::remove_dir_all(&d);
    d
}

/// Runs `train` with `args` (which write the run to `run`), asserts that it
/// succeeded (`what` names it in the failure) and returns the run's
/// config.json.
#[cfg(feature = "train")]
fn train_config(args: &[&str], run: &std::path::Path, what: &str) -> serde_json::Value {
    let out = naosoccer(args);
    assert!(
        out.status.success(),
        "{what}: train failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_str(&std::fs::read_to_string(run.join("config.json")).unwrap()).unwrap()
}

#[cfg(feature = "train")]
#[test]
fn train_eval_plot_round_trip() {
    let run = dir("cli_ppo_run");
    let run_s = run.to_str().unwrap();
    let out = naosoccer(&[
        "train",
        "--algo",
        "ppo",
        "--steps",
        "2048",
        "--seed",
        "3",
        "--matches",
        "4",
        "--rollout",
        "32",
        "--epochs",
        "2",
        "--minutes",
        "0.1",
        "--checkpoint-every",
        "1024",
        "--out",
        run_s,
    ]);
    assert!(
        out.status.success(),
        "train failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    for f in [
        "config.json",
        "metrics.csv",
        "final.safetensors",
        "checkpoints/step-1024.safetensors",
    ] {
        assert!(run.join(f).exists(), "{f} written");
    }
    let metrics = std::fs::read_to_string(run.join("metrics.csv")).unwrap();
    assert!(
        metrics.starts_with("update,timeslot,transitions"),
        "{metrics}"
    );
    assert_eq!(
        metrics.lines().count(),
        1 + 2048 / (4 * 4 * 32),
        "{metrics}"
    );

    let spec = format!("ppo:{run_s}");
    let out = naosoccer(&[
        "eval",
        "--blue",
        &spec,
        "--red",
        "scripted",
        "--matches",
        "3",
        "--minutes",
        "0.2",
        "--seed",
        "1",
        "--json",
    ]);
    assert!(
        out.status.success(),
        "eval failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value =
        serde_json::from_slice(&out.stdout).expect("eval --json prints one JSON object");
    assert_eq!(v["matches"], 3);
    assert_eq!(v["scores"].as_array().unwrap().len(), 3);
    let blue = v["blue"]["control_rate_percent"]["mean"].as_f64().unwrap();
    let red = v["red"]["control_rate_percent"]["mean"].as_f64().unwrap();
    assert!((0.0..=100.0).contains(&blue) && (0.0..=100.0).contains(&red));

    let png = run.join("curves.png");
    let out = naosoccer(&["plot", run_s, "--out", png.to_str().unwrap()]);
    assert!(
        out.status.success(),
        "plot failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let bytes = std::fs::read(&png).unwrap();
    assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n", "a PNG file");
}

#[cfg(feature = "train")]
#[test]
fn bad_input_gives_clear_errors() {
    let out = naosoccer(&["train", "--algo", "sarsa", "--out", "x"]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("expected dqn or ppo"));

    let out = naosoccer(&[
        "eval",
        "--blue",
        "ppo:/nonexistent-run-dir",
        "--matches",
        "1",
    ]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("nonexistent-run-dir"), "{err}");

    let out = naosoccer(&["eval", "--blue", "wizard", "--matches", "1"]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("unknown policy"));

    // Scripted variants: unknown keys and bad values, wherever a spec goes.
    for args in [
        &["eval", "--blue", "scripted:shot_range=3", "--matches", "1"][..],
        &[
            "match",
            "--red",
            "scripted:shot_range=3",
            "--minutes",
            "0.05",
        ][..],
        &[
            "train",
            "--algo",
            "dqn",
            "--opponent",
            "scripted:shot_range=3",
            "--out",
            "x",
        ][..],
    ] {
        let out = naosoccer(args);
        assert!(!out.status.success(), "{args:?}");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(
            err.contains("unknown scripted parameter \"shot_range\""),
            "{args:?}: {err}"
        );
    }
    let out = naosoccer(&["eval", "--blue", "scripted:b_shoot=wide", "--matches", "1"]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("b_shoot: \"wide\" is not a number"), "{err}");
    let out = naosoccer(&[
        "train", "--algo", "dqn", "--preset", "rainbow", "--out", "x",
    ]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("unknown DQN preset"), "{err}");
    // A weight average: DQN only, and a fraction below 1.
    for (args, needle) in [
        (&["--algo", "ppo", "--average", "0.999"][..], "a DQN option"),
        (
            &["--algo", "dqn", "--average", "1"][..],
            "must be in [0, 1)",
        ),
        (
            &["--algo", "dqn", "--average=-0.5"][..],
            "must be in [0, 1)",
        ),
    ] {
        let out = naosoccer(&[&["train", "--out", "x"][..], args].concat());
        assert!(!out.status.success(), "{args:?}");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains(needle), "{args:?}: {err}");
    }
}

/// The pass-aware and shot-aware observation layouts (versions 3 and 4):
/// PPO and DQN train on them, the run records its layout, its team plays in
/// `eval`, and a checkpoint whose layout this build cannot encode is refused
/// with a message naming it.
#[cfg(feature = "train")]
#[test]
fn observation_layouts_3_and_4_train_play_and_unknown_layouts_are_refused() {
    for (algo, version) in [("ppo", 3), ("dqn", 3), ("ppo", 4), ("dqn", 4)] {
        let run = dir(&format!("cli_obs{version}_{algo}"));
        let run_s = run.to_str().unwrap();
        let out = naosoccer(&[
            "train",
            "--algo",
            algo,
            "--preset",
            "team",
            "--obs-version",
            &version.to_string(),
            "--steps",
            "2048",
            "--seed",
            "5",
            "--matches",
            "4",
            "--minutes",
            "0.1",
            "--out",
            run_s,
        ]);
        assert!(
            out.status.success(),
            "{algo}: train failed: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        let config_path = run.join("config.json");
        let mut config: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&config_path).unwrap()).unwrap();
        assert_eq!(
            config["obs_version"], version,
            "{algo}: the run records its layout"
        );

        let spec = format!("{algo}:{run_s}");
        let eval = |spec: &str| {
            naosoccer(&[
                "eval",
                "--blue",
                spec,
                "--red",
                "scripted",
                "--matches",
                "1",
                "--minutes",
                "0.1",
                "--seed",
                "2",
            ])
        };
        let out = eval(&spec);
        assert!(
            out.status.success(),
            "{algo}: eval failed: {}",
            String::from_utf8_lossy(&out.stderr)
        );

        config["obs_version"] = serde_json::json!(9);
        std::fs::write(&config_path, config.to_string()).unwrap();
        let out = eval(&spec);
        assert!(!out.status.success(), "{algo}: layout 9 must be refused");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(
            err.contains("observation layout v9") && err.contains("v1 to v4"),
            "{algo}: {err}"
        );
    }
}

/// `--gamma` and `--lr` set DQN's discount and learning rate as they set
/// PPO's (before, a DQN run ignored them), and land in config.json; a
/// discount outside (0, 1] is refused.
#[cfg(feature = "train")]
#[test]
fn gamma_and_lr_reach_a_dqn_run() {
    for (algo, preset) in [("dqn", "team"), ("ppo", "team")] {
        let run = dir(&format!("cli_gamma_{algo}"));
        let mut args = short_train(algo, preset, "2");
        args.extend(["--gamma", "0.98", "--lr", "0.0005"]);
        let run_s = run.to_str().unwrap().to_string();
        let mut full: Vec<&str> = args.clone();
        full.extend(["--out", &run_s]);
        let cfg = train_config(&full, &run, algo);
        let section = &cfg[algo];
        assert_eq!(section["gamma"].as_f64(), Some(0.98), "{algo}: {section}");
        let lr = if algo == "dqn" { "lr" } else { "lr_actor" };
        assert_eq!(section[lr].as_f64(), Some(0.0005), "{algo}: {section}");
    }
    let out = naosoccer(&["train", "--algo", "dqn", "--gamma", "1.5", "--out", "x"]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("--gamma must be in (0, 1]"), "{err}");
}

/// A shipped team's directory under assets/policies/.
#[cfg(feature = "train")]
fn shipped_policy(name: &str) -> String {
    format!("{}/assets/policies/{name}", env!("CARGO_MANIFEST_DIR"))
}

/// A test-sized `train` on observation layout 3: 2,048 transitions, four
/// six-second matches.
#[cfg(feature = "train")]
fn short_train(algo: &'static str, preset: &'static str, seed: &'static str) -> Vec<&'static str> {
    vec![
        "train",
        "--algo",
        algo,
        "--preset",
        preset,
        "--obs-version",
        "3",
        "--steps",
        "2048",
        "--seed",
        seed,
        "--matches",
        "4",
        "--minutes",
        "0.1",
    ]
}

/// `--entropy-coef-end`: the weight PPO's entropy bonus falls to by the
/// run's end, recorded in config.json (the team preset's own 0.002 when
/// not given), and refused when negative.
#[cfg(feature = "train")]
#[test]
fn the_entropy_weight_at_the_end_is_an_option() {
    let run = dir("cli_entropy_end");
    let run_s = run.to_str().unwrap();
    let mut a = short_train("ppo", "team", "5");
    a.extend([
        "--entropy-coef",
        "0.02",
        "--entropy-coef-end",
        "0.005",
        "--out",
        run_s,
    ]);
    let config = train_config(&a, &run, "ppo with --entropy-coef-end");
    assert_eq!(config["ppo"]["entropy_coef"], 0.02);
    assert_eq!(config["ppo"]["entropy_coef_end"], 0.005);

    let plain = dir("cli_entropy_end_default");
    let plain_s = plain.to_str().unwrap();
    let mut a = short_train("ppo", "team", "5");
    a.extend(["--out", plain_s]);
    let config = train_config(&a, &plain, "ppo team");
    assert_eq!(config["ppo"]["entropy_coef_end"], 0.002);

    let mut a = short_train("ppo", "team", "5");
    a.extend(["--entropy-coef-end=-0.1", "--out", plain_s]);
    let out = naosoccer(&a);
    assert!(!out.status.success(), "a negative weight must be refused");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("--entropy-coef-end must be a weight of 0 or more"),
        "{err}"
    );
}

/// `train --pass-action --support-action --support-hold 40 --support-roles 2
/// --support-only --support-spot facing --approach-action --approach-only
/// --init-from --pass-init turn_left --support-init-bias 0`: a shipped team
/// seeds a run with `pass`, a held `support`, roles and `approach`; the run
/// records them all and where `pass` and `support` started, and plays over
/// the socket-free eval path; `--support-action` alone is refused, as are
/// `--approach-action`, `--approach-only` (without `--approach-action`),
/// `--support-spot` and an unknown spot,
/// `--support-hold`, `--support-roles` and `--support-init-bias` without
/// it, the support action without the team preset, and `--pass-init`
/// without `--init-from`.
#[cfg(feature = "train")]
#[test]
fn support_action_runs_start_from_a_shipped_team_and_play() {
    let run = dir("cli_support_action");
    let run_s = run.to_str().unwrap();
    let shipped = shipped_policy("ppo-team-v3-seed2");
    let base = short_train("ppo", "team", "6");
    let mut a = base.to_vec();
    a.extend([
        "--pass-action",
        "--support-action",
        "--support-hold",
        "40",
        "--support-roles",
        "2",
        "--support-only",
        "--support-spot",
        "facing",
        "--approach-action",
        "--approach-only",
        "--init-from",
        &shipped,
        "--pass-init",
        "turn_left",
        "--support-init-bias",
        "0",
        "--out",
        run_s,
    ]);
    let config = train_config(&a, &run, "ppo");
    assert_eq!(config["ppo"]["decision"]["pass"], true);
    assert_eq!(config["ppo"]["decision"]["support"], true);
    assert_eq!(config["ppo"]["decision"]["support_hold"], 40);
    assert_eq!(config["ppo"]["decision"]["chasers"], 2);
    assert_eq!(config["ppo"]["decision"]["support_only"], true);
    assert_eq!(config["ppo"]["decision"]["support_spot"], "facing");
    assert_eq!(config["ppo"]["decision"]["approach"], true);
    assert_eq!(config["ppo"]["decision"]["approach_only"], true);
    assert_eq!(config["init_pass_from"], "turn_left");
    assert_eq!(config["init_support_bias"], 0.0);
    plays_a_match(&format!("ppo:{run_s}"));

    let other = dir("cli_support_action_refused");
    let other_s = other.to_str().unwrap();
    // `extra` after the short run's arguments is refused, with a message
    // naming `needle`.
    let refused = |extra: &[&str], needle: &str, why: &str| {
        let mut a = base.to_vec();
        a.extend_from_slice(extra);
        a.extend(["--out", other_s]);
        let out = naosoccer(&a);
        assert!(!out.status.success(), "{why}");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains(needle), "{err}");
    };
    refused(
        &["--support-action"],
        "--pass-action",
        "--support-action alone must be refused",
    );
    refused(
        &["--pass-action", "--support-hold", "40"],
        "--support-action",
        "--support-hold needs --support-action",
    );
    refused(
        &[
            "--pass-action",
            "--init-from",
            &shipped,
            "--support-init-bias",
            "0",
        ],
        "--support-action",
        "--support-init-bias needs --support-action",
    );
    refused(
        &["--pass-action", "--support-roles", "1"],
        "--support-action",
        "--support-roles needs --support-action",
    );
    refused(
        &["--pass-action", "--pass-init", "turn_left"],
        "--init-from",
        "--pass-init needs --init-from",
    );
    refused(
        &["--pass-action", "--approach-action"],
        "--support-action",
        "--approach-action needs --support-action",
    );
    refused(
        &["--pass-action", "--support-action", "--approach-only"],
        "--approach-action",
        "--approach-only needs --approach-action",
    );
    refused(
        &["--pass-action", "--support-spot", "facing"],
        "--support-action",
        "--support-spot needs --support-action",
    );
    refused(
        &[
            "--pass-action",
            "--support-action",
            "--support-spot",
            "behind",
        ],
        "facing",
        "--support-spot takes ahead or facing",
    );
    let mut a = base.to_vec();
    a[4] = "cleanrl";
    a.extend(["--pass-action", "--support-action", "--out", other_s]);
    let out = naosoccer(&a);
    assert!(
        !out.status.success(),
        "cleanrl must refuse --support-action"
    );
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("--support-action") && err.contains("team preset"),
        "{err}"
    );
}

/// `train --pass-action --init-from`: a shipped team (five actions) seeds a
/// run with the sixth action, `pass`; the run records both, trains, and
/// plays; DQN's team preset trains and plays with the actions too; the
/// non-team presets refuse the flags by name.
#[cfg(feature = "train")]
#[test]
fn pass_action_runs_start_from_a_shipped_team_and_play() {
    let run = dir("cli_pass_action");
    let run_s = run.to_str().unwrap();
    let shipped = shipped_policy("ppo-team-v3-seed1");
    let args = |algo: &'static str, preset: &'static str| {
        let mut a = short_train(algo, preset, "5");
        a.push("--pass-action");
        a
    };
    let mut a = args("ppo", "team");
    a.extend(["--init-from", &shipped, "--out", run_s]);
    let config = train_config(&a, &run, "ppo");
    assert_eq!(config["ppo"]["decision"]["pass"], true);
    assert_eq!(config["init_from"], serde_json::json!(shipped));
    plays_a_match(&format!("ppo:{run_s}"));

    // DQN's team preset takes the actions too (issue 40): it trains and
    // its team plays them.
    let dqn = dir("cli_pass_action_dqn");
    let dqn_s = dqn.to_str().unwrap();
    let mut a = args("dqn", "team");
    a.extend(["--support-action", "--defend-action", "--out", dqn_s]);
    let config = train_config(&a, &dqn, "dqn");
    let decision = &config["dqn"]["decision"];
    for flag in ["pass", "support", "defend"] {
        assert_eq!(decision[flag], true, "{flag}: {decision}");
    }
    plays_a_match(&format!("dqn:{dqn_s}"));

    let other = dir("cli_pass_action_refused");
    let other_s = other.to_str().unwrap();
    for (algo, preset, says) in [
        ("dqn", "paper", "team preset"),
        ("ppo", "cleanrl", "team preset"),
    ] {
        let mut a = args(algo, preset);
        a.extend(["--out", other_s]);
        let out = naosoccer(&a);
        assert!(
            !out.status.success(),
            "{algo} {preset} must refuse --pass-action"
        );
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(
            err.contains("pass") && err.contains(says),
            "{algo} {preset}: {err}"
        );
    }
    // A network of another shape is named, not loaded.
    let mut a = args("ppo", "team");
    let paper = shipped_policy("ppo-paper-seed1");
    a.extend(["--init-from", &paper, "--out", other_s]);
    let out = naosoccer(&a);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("--init-from") && err.contains("actor."),
        "{err}"
    );
}

/// `eval --both-sides` against a shipped scripted variant: each team keeps
/// its name, half the matches swap the sides, the win rate carries its
/// Wilson interval, and the seeds are evaluation seeds.
#[test]
fn eval_both_sides_reports_each_team_under_its_name() {
    let variant = concat!(env!("CARGO_MANIFEST_DIR"), "/assets/scripted/press.toml");
    let spec = format!("scripted:{variant}");
    let run = |extra: &[&str]| {
        let mut args = vec![
            "eval",
            "--blue",
            &spec,
            "--red",
            "random",
            "--matches",
            "4",
            "--minutes",
            "0.2",
            "--seed",
            "5",
            "--json",
        ];
        args.extend_from_slice(extra);
        let out = naosoccer(&args);
        assert!(
            out.status.success(),
            "eval failed: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        serde_json::from_slice::<serde_json::Value>(&out.stdout).unwrap()
    };
    let v = run(&["--both-sides"]);
    assert_eq!(v["both_sides"], true);
    assert_eq!(v["seed_scheme"], "eval");
    assert_eq!(v["swapped"], serde_json::json!([false, true, false, true]));
    assert_eq!(v["blue"]["name"], spec.as_str());
    assert_eq!(v["red"]["name"], "random");
    for team in ["blue", "red"] {
        let t = &v[team];
        let (w, d, l) = (
            t["wins"].as_u64().unwrap(),
            t["draws"].as_u64().unwrap(),
            t["losses"].as_u64().unwrap(),
        );
        assert_eq!(w + d + l, 4);
        for side in ["as_blue", "as_red"] {
            let r = &t[side];
            let n = r["wins"].as_u64().unwrap()
                + r["draws"].as_u64().unwrap()
                + r["losses"].as_u64().unwrap();
            assert_eq!(n, 2, "{team} {side}");
        }
        let rate = &t["win_rate"];
        let (low, p, high) = (
            rate["low"].as_f64().unwrap(),
            rate["rate"].as_f64().unwrap(),
            rate["high"].as_f64().unwrap(),
        );
        assert!((p - w as f64 / 4.0).abs() < 1e-12);
        assert!(0.0 <= low && low <= p && p <= high && high <= 1.0);
    }
    // Scores list the first team's goals first whichever colour it played.
    let goals: u64 = v["scores"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| s[0].as_u64().unwrap())
        .sum();
    assert!((v["blue"]["goals"]["mean"].as_f64().unwrap() - goals as f64 / 4.0).abs() < 1e-12);
    // The matches not swapped are the plain evaluation's.
    let plain = run(&[]);
    assert_eq!(plain["both_sides"], false);
    for i in [0, 2] {
        assert_eq!(plain["scores"][i], v["scores"][i]);
    }
    // Legacy seeds are other matches (the old derivation, kept for replays).
    let legacy = run(&["--legacy-seeds"]);
    assert_eq!(legacy["seed_scheme"], "legacy");
}

/// `naosoccer match` plays a shipped trained team in process and records
/// it; the recording replays identically, and the same seed gives the same
/// match (sampled PPO draws are seeded by the match seed).
#[test]
fn match_plays_a_trained_team_and_records_it() {
    let rec = dir("match_trained");
    std::fs::create_dir_all(&rec).unwrap();
    let file = rec.join("ppo.mcap");
    let f = file.to_str().unwrap();
    let policy = format!(
        "ppo:{}/assets/policies/ppo-paper-seed1",
        env!("CARGO_MANIFEST_DIR")
    );
    let play = |record: Option<&str>| {
        let mut args = vec![
            "match",
            "--blue",
            &policy,
            "--red",
            "scripted",
            "--seed",
            "4",
            "--minutes",
            "0.5",
            "--json",
        ];
        if let Some(f) = record {
            args.extend(["--record", f]);
        }
        let out = naosoccer(&args);
        assert!(
            out.status.success(),
            "match failed: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        serde_json::from_slice::<serde_json::Value>(&out.stdout).unwrap()
    };
    let a = play(Some(f));
    let b = play(None);
    assert_eq!(a["state_hash"], b["state_hash"], "same seed, same match");
    assert_eq!(a["ticks"], 300);

    let out = naosoccer(&["replay", f]);
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert_eq!(
        String::from_utf8_lossy(&out.stdout).trim(),
        "identical (300 ticks)"
    );

    let out = naosoccer(&["match", "--blue", "ppo:/nonexistent-run-dir"]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("loading --blue ppo:/nonexistent-run-dir"),
        "{err}"
    );
}

/// A build without libtorch still knows `train`, `plot` and `bench learn`,
/// whatever their arguments, and says exactly what to run instead.
#[cfg(not(feature = "train"))]
#[test]
fn training_commands_without_the_feature_say_what_to_run() {
    for args in [
        &["train", "--algo", "ppo", "--out", "runs/x"][..],
        &["train", "--help"][..],
        &["plot", "runs/x", "--out", "x.png"][..],
        &["bench", "learn"][..],
    ] {
        let out = naosoccer(args);
        assert!(!out.status.success(), "{args:?} cannot succeed here");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains("needs libtorch"), "{args:?}: {err}");
        assert!(err.contains("scripts/setup"), "{args:?}: {err}");
        assert!(
            err.contains("cargo build --release --features train"),
            "{args:?}: {err}"
        );
        let want = format!("target/release/naosoccer {}", args.join(" "));
        assert!(err.contains(&want), "{args:?}: {err}");
    }
}

/// The default build links no libtorch (issue 14): `ldd` lists none of its
/// libraries for the binary (where `ldd` exists).
#[cfg(not(feature = "train"))]
#[test]
fn the_default_build_links_no_libtorch() {
    let Ok(out) = std::process::Command::new("ldd")
        .arg(env!("CARGO_BIN_EXE_naosoccer"))
        .output()
    else {
        eprintln!("no ldd here; nothing to check");
        return;
    };
    let libs = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "ldd failed: {libs}");
    assert!(
        !libs.contains("torch") && !libs.contains("libc10"),
        "the default build links libtorch:\n{libs}"
    );
}

/// `train --recipe`: both stages of a two-stage recipe run in one command
/// (the second from the first's weights) and the team lands in the run
/// directory with its time file; a run stopped between the stages and
/// continued with `--resume` skips the finished stage and writes the same
/// final weights, and so does one continued with another `--threads`; a
/// second start on the same directory is refused, and a bad recipe is
/// refused before anything is trained.
#[cfg(feature = "train")]
#[test]
fn a_recipe_runs_every_stage_and_resumes_between_them() {
    let recipe = dir("recipe_file").with_extension("toml");
    std::fs::write(
        &recipe,
        r#"description = "two tiny stages"
[[stage]]
name = "first"
algo = "ppo"
preset = "team"
minutes = 0.1
steps = 2048
matches = 4
rollout = 32
epochs = 2
checkpoint-every = 1024
[[stage]]
name = "second"
algo = "ppo"
preset = "team"
init-from = "previous"
minutes = 0.1
steps = 2048
matches = 4
rollout = 32
epochs = 2
lr = 0.0001
checkpoint-every = 512
scenarios = ["PASS0", "PASS1"]
scenario-matches = 2
"#
        .replace("PASS0", &pass_drill(0))
        .replace("PASS1", &pass_drill(1)),
    )
    .unwrap();
    let recipe_s = recipe.to_str().unwrap();
    let whole = dir("recipe_whole");
    let out = naosoccer(&[
        "train",
        "--recipe",
        recipe_s,
        "--out",
        whole.to_str().unwrap(),
        "--seed",
        "5",
        "--threads",
        "1",
    ]);
    assert!(out.status.success(), "{}", common::text(&out));
    for f in [
        "recipe.toml",
        "recipe-run.json",
        "time.json",
        "config.json",
        "final.safetensors",
        "01-first/final.safetensors",
        "02-second/final.safetensors",
    ] {
        assert!(whole.join(f).exists(), "{f} written");
    }
    let second_cfg = std::fs::read_to_string(whole.join("02-second/config.json")).unwrap();
    assert!(second_cfg.contains("01-first"), "{second_cfg}");
    // The recipe's list of scenarios: the run keeps each file's name and text.
    let second: serde_json::Value = serde_json::from_str(&second_cfg).unwrap();
    assert_eq!(second["threads"], 1, "--threads reaches every stage");
    let scenarios = &second["scenarios"];
    assert_eq!(scenarios["matches"], 2, "{second_cfg}");
    assert_eq!(scenarios["scenarios"][0]["name"], "pass-0");
    assert_eq!(scenarios["scenarios"][1]["name"], "pass-1");
    assert!(scenarios["scenarios"][1]["text"]
        .as_str()
        .unwrap()
        .contains("direction"));
    let time: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(whole.join("time.json")).unwrap()).unwrap();
    assert_eq!(time["sittings"], 1);
    assert_eq!(time["cpu_models"].as_array().unwrap().len(), 1, "{time}");
    assert_eq!(time["stages"].as_array().unwrap().len(), 2);
    assert!(time["total_seconds"].as_f64().unwrap() > 0.0, "{time}");
    let final_whole = std::fs::read(whole.join("final.safetensors")).unwrap();
    assert_eq!(
        final_whole,
        std::fs::read(whole.join("02-second/final.safetensors")).unwrap()
    );

    // The same run stopped after its first stage, then continued.
    let split = dir("recipe_split");
    std::fs::create_dir_all(split.join("01-first")).unwrap();
    for f in ["recipe.toml", "recipe-run.json"] {
        std::fs::copy(whole.join(f), split.join(f)).unwrap();
    }
    for e in std::fs::read_dir(whole.join("01-first")).unwrap() {
        let e = e.unwrap();
        if e.file_type().unwrap().is_file() {
            std::fs::copy(e.path(), split.join("01-first").join(e.file_name())).unwrap();
        }
    }
    // The first stage's config names the directory it was trained in; the
    // second stage starts from the split run's own first stage.
    let out = naosoccer(&["train", "--resume", split.to_str().unwrap()]);
    assert!(out.status.success(), "{}", common::text(&out));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("stage 1/2 first: done"), "{err}");
    assert!(err.contains("stage 2/2 second: starting"), "{err}");
    assert_eq!(
        std::fs::read(split.join("final.safetensors")).unwrap(),
        final_whole,
        "a recipe continued after a stop writes the same team"
    );

    // The same run stopped inside its second stage, after its first
    // checkpoint: it continues from that checkpoint, not from scratch.
    let mid = dir("recipe_mid");
    for stage in ["01-first", "02-second"] {
        std::fs::create_dir_all(mid.join(stage).join("checkpoints")).unwrap();
    }
    for f in ["recipe.toml", "recipe-run.json", "time.json"] {
        std::fs::copy(whole.join(f), mid.join(f)).unwrap();
    }
    let copy_files = |from: &std::path::Path, to: &std::path::Path, keep: &dyn Fn(&str) -> bool| {
        for e in std::fs::read_dir(from).unwrap() {
            let e = e.unwrap();
            let name = e.file_name().to_string_lossy().into_owned();
            if e.file_type().unwrap().is_file() && keep(&name) {
                std::fs::copy(e.path(), to.join(&name)).unwrap();
            }
        }
    };
    copy_files(&whole.join("01-first"), &mid.join("01-first"), &|_| true);
    copy_files(&whole.join("02-second"), &mid.join("02-second"), &|n| {
        n != "final.safetensors"
    });
    let mut steps: Vec<u64> = std::fs::read_dir(whole.join("02-second/checkpoints"))
        .unwrap()
        .filter_map(|e| {
            let name = e.unwrap().file_name().to_string_lossy().into_owned();
            name.strip_prefix("step-")?
                .strip_suffix(".resume.json")?
                .parse()
                .ok()
        })
        .collect();
    steps.sort_unstable();
    assert!(steps.len() >= 2, "checkpoints inside the stage: {steps:?}");
    let first = format!("step-{}.", steps[0]);
    copy_files(
        &whole.join("02-second/checkpoints"),
        &mid.join("02-second/checkpoints"),
        &|n| n.starts_with(&first),
    );
    // On three threads this time: the count changes nothing learned.
    let out = naosoccer(&["train", "--resume", mid.to_str().unwrap(), "--threads", "3"]);
    assert!(out.status.success(), "{}", common::text(&out));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("stage 2/2 second: continuing from its latest checkpoint"),
        "{err}"
    );
    let mid_cfg: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(mid.join("02-second/config.json")).unwrap())
            .unwrap();
    assert_eq!(mid_cfg["threads"], 3, "the continued stage's thread count");
    let mid_time: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(mid.join("time.json")).unwrap()).unwrap();
    assert_eq!(mid_time["sittings"], 2, "{mid_time}");
    assert_eq!(
        mid_time["cpu_models"].as_array().unwrap().len(),
        2,
        "{mid_time}"
    );
    assert_eq!(
        std::fs::read(mid.join("final.safetensors")).unwrap(),
        final_whole,
        "a recipe continued from a checkpoint inside a stage writes the same team"
    );

    let again = naosoccer(&[
        "train",
        "--recipe",
        recipe_s,
        "--out",
        whole.to_str().unwrap(),
    ]);
    assert!(!again.status.success());
    assert!(
        common::text(&again).contains("already holds a recipe run"),
        "{}",
        common::text(&again)
    );

    let bad = dir("recipe_bad").with_extension("toml");
    std::fs::write(
        &bad,
        "[[stage]]\nname = \"a\"\nalgo = \"ppo\"\ninit-from = \"assets/policies/ppo-team-seed1\"\n",
    )
    .unwrap();
    let empty = dir("recipe_bad_out");
    let out = naosoccer(&[
        "train",
        "--recipe",
        bad.to_str().unwrap(),
        "--out",
        empty.to_str().unwrap(),
    ]);
    assert!(!out.status.success());
    let text = common::text(&out);
    assert!(
        text.contains("init-from") && text.contains("from scratch"),
        "{text}"
    );
    assert!(!empty.exists(), "nothing written for a bad recipe");
    let out = naosoccer(&["train", "--recipe", recipe_s, "--steps", "5"]);
    assert!(!out.status.success(), "options beside --recipe are refused");
    let out = naosoccer(&[
        "train",
        "--recipe",
        recipe_s,
        "--out",
        "x",
        "--threads",
        "0",
    ]);
    assert!(!out.status.success(), "no threads at all is refused");
}

/// `eval` plays one short match of the team `spec` against `scripted`.
#[cfg(feature = "train")]
fn plays_a_match(spec: &str) {
    let out = naosoccer(&[
        "eval",
        "--blue",
        spec,
        "--red",
        "scripted",
        "--matches",
        "1",
        "--minutes",
        "0.2",
    ]);
    assert!(
        out.status.success(),
        "eval of {spec} failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// A shipped pass drill's path (assets/scenarios/training/pass-K.toml).
#[cfg(feature = "train")]
fn pass_drill(k: usize) -> String {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join(format!("assets/scenarios/training/pass-{k}.toml"))
        .to_str()
        .unwrap()
        .to_owned()
}

/// `train --scenarios`: a missing or bad scenario file, or scenarios
/// without the PPO team preset, are refused before anything is trained,
/// naming what is wrong.
#[cfg(feature = "train")]
#[test]
fn train_refuses_bad_scenarios() {
    let out_dir = dir("scenarios_bad");
    let base = [
        "train",
        "--algo",
        "ppo",
        "--preset",
        "team",
        "--minutes",
        "0.1",
        "--steps",
        "64",
        "--matches",
        "4",
        "--out",
    ];
    let bad = dir("scenario_bad").with_extension("toml");
    std::fs::write(&bad, "[ball]\nx = 9.0\ny = 0.0\n").unwrap();
    for (scenarios, matches, expect) in [
        ("no-such-drill.toml".to_owned(), "2", "no-such-drill.toml"),
        (bad.to_str().unwrap().to_owned(), "2", "ball.x"),
        (pass_drill(0), "5", "between 1 and the 4 matches"),
    ] {
        let mut args = base.to_vec();
        args.extend([
            out_dir.to_str().unwrap(),
            "--scenarios",
            &scenarios,
            "--scenario-matches",
            matches,
        ]);
        let out = naosoccer(&args);
        assert!(!out.status.success(), "{scenarios}");
        let text = common::text(&out);
        assert!(text.contains(expect), "{expect}: {text}");
        assert!(!out_dir.join("final.safetensors").exists());
    }
    let out = naosoccer(&[
        "train",
        "--algo",
        "dqn",
        "--preset",
        "team",
        "--minutes",
        "0.1",
        "--steps",
        "64",
        "--out",
        out_dir.to_str().unwrap(),
        "--scenarios",
        &pass_drill(0),
        "--scenario-matches",
        "2",
    ]);
    assert!(!out.status.success());
    assert!(
        common::text(&out).contains("PPO team preset"),
        "{}",
        common::text(&out)
    );
}
