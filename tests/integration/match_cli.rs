//! `naosoccer match` end to end: the real binary, its JSON and its table.

use crate::common;

use common::naosoccer;

#[test]
fn json_is_one_object_with_the_documented_fields() {
    let out = naosoccer(&["match", "--seed", "5", "--minutes", "1", "--json"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8(out.stdout).unwrap();
    assert_eq!(text.trim().lines().count(), 1, "{text}");
    let v: serde_json::Value = serde_json::from_str(&text).unwrap();
    let keys: Vec<&str> = v.as_object().unwrap().keys().map(String::as_str).collect();
    let mut want = vec![
        "seed",
        "ticks",
        "sim_seconds",
        "wall_seconds",
        "score",
        "stats",
        "state_hash",
    ];
    want.sort();
    let mut got = keys.clone();
    got.sort();
    assert_eq!(got, want);
    assert_eq!(v["seed"], 5);
    assert_eq!(v["ticks"], 600);
    assert_eq!(v["sim_seconds"], 60.0);
    for team in ["blue", "red"] {
        let s = &v["stats"][team];
        for k in [
            "goals",
            "control_rate",
            "passes",
            "aimed_passes",
            "shots",
            "falls",
            "out_of_bounds",
        ] {
            assert!(s[k].is_number(), "stats.{team}.{k} in {s}");
        }
        assert_eq!(v["score"][team], s["goals"]);
    }
    let hash = v["state_hash"].as_str().unwrap();
    assert_eq!(hash.len(), 16);
    assert!(hash.chars().all(|c| c.is_ascii_hexdigit()));
    // Same seed, same match.
    let again = naosoccer(&["match", "--seed", "5", "--minutes", "1", "--json"]);
    let w: serde_json::Value = serde_json::from_slice(&again.stdout).unwrap();
    assert_eq!(v["state_hash"], w["state_hash"]);
    assert_eq!(v["stats"], w["stats"]);
}

#[test]
fn table_shows_score_and_statistics() {
    let out = naosoccer(&[
        "match",
        "--seed",
        "2",
        "--minutes",
        "0.5",
        "--blue",
        "random",
        "--red",
        "idle",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8(out.stdout).unwrap();
    for needle in [
        "final score: blue",
        "ball control",
        "passes",
        "shots",
        "falls",
        "out of bounds",
        "random (blue) vs idle (red)",
    ] {
        assert!(text.contains(needle), "{needle:?} missing in\n{text}");
    }
    // Not a terminal: no progress line.
    assert!(
        out.stderr.is_empty(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

#[test]
fn bad_input_is_a_clear_error() {
    let out = naosoccer(&["match", "--blue", "striker"]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("striker") && err.contains("scripted"), "{err}");
    let dir = std::env::temp_dir().join(format!("naosoccer-match-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let cfg = dir.join("bad.toml");
    std::fs::write(&cfg, "[rules]\nb_rad = -0.5\n").unwrap();
    let out = naosoccer(&["match", "--config", cfg.to_str().unwrap()]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("rules.b_rad"), "{err}");
    let out = naosoccer(&["match", "--minutes", "0"]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("match.minutes"));
    // A TOML error is reported once, not once per layer of the error chain.
    std::fs::write(&cfg, "[match]\nminutes = \"x\"\n").unwrap();
    for cmd in [
        &["match"][..],
        &["eval", "--blue", "scripted", "--matches", "1"][..],
    ] {
        let mut args = cmd.to_vec();
        args.extend(["--config", cfg.to_str().unwrap()]);
        let out = naosoccer(&args);
        assert!(!out.status.success());
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(err.matches("TOML parse error").count(), 1, "{err}");
        assert_eq!(err.matches("expected f32").count(), 1, "{err}");
    }
    // A team directory that does not exist is called missing.
    let missing = dir.join("no-such-team");
    let spec = format!("ppo:{}", missing.display());
    let out = naosoccer(&["match", "--blue", &spec]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("no such directory"), "{err}");
    // `--config` is the match configuration for `server` too: a server
    // configuration given there is named, with the option it belongs to.
    let srv = dir.join("server.toml");
    std::fs::write(&srv, "port = 0\nmatches = 1\n").unwrap();
    let out = naosoccer(&["server", "--config", srv.to_str().unwrap()]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("--server-config") && err.contains("port"),
        "{err}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}
