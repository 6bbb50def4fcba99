//! Ctrl-C keeps what a command has done: `match --record` leaves a finished,
//! readable recording and prints the match so far, `eval` prints (or with
//! `--json` writes) the matches already played; both exit with 130. Output
//! piped into a reader that stops early ends the command quietly.
//!
//! The signal is sent once the command has installed its handler, which the
//! test reads from /proc (Linux), so no test waits on a guessed duration.

use std::io::Read;
use std::process::{Child, Stdio};

use crate::common::{naosoccer, naosoccer_cmd, scratch, text};

/// Waits until `child` handles SIGINT (bit 2 of SigCgt in /proc/PID/status).
fn wait_for_handler(child: &Child) {
    let status = format!("/proc/{}/status", child.id());
    loop {
        let text = std::fs::read_to_string(&status).expect("read /proc status");
        let caught = text
            .lines()
            .find_map(|l| l.strip_prefix("SigCgt:"))
            .map(|v| u64::from_str_radix(v.trim(), 16).expect("hex mask"))
            .expect("SigCgt line");
        if caught & (1 << (libc_sigint() - 1)) != 0 {
            return;
        }
        // Polling a condition, not timing it: the pause only spares the CPU.
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
}

/// Waits until `child` has used `secs` of CPU time (user + system, from
/// /proc/PID/stat, in clock ticks of 1/100 s).
fn wait_for_cpu_seconds(child: &Child, secs: f64) {
    let stat = format!("/proc/{}/stat", child.id());
    loop {
        let text = std::fs::read_to_string(&stat).expect("read /proc stat");
        // Fields after the command name (which is in parentheses).
        let rest = &text[text.rfind(')').expect("comm") + 2..];
        let f: Vec<&str> = rest.split_whitespace().collect();
        let ticks: f64 = f[11].parse::<f64>().unwrap() + f[12].parse::<f64>().unwrap();
        if ticks / 100.0 >= secs {
            return;
        }
        // Polling a condition, not timing it: the pause only spares the CPU.
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
}

fn libc_sigint() -> u32 {
    2
}

/// `cmd` with Ctrl-C's default action restored in the child. A shell that
/// starts a command in the background without job control (`scripts/test &`
/// in a script) ignores SIGINT in it, the programs it starts inherit that,
/// and `train`, which keeps the default action (it stops at once and
/// resumes from its last checkpoint), would then not stop: the test would
/// depend on how the suite was started.
#[cfg(all(target_os = "linux", feature = "train"))]
fn with_default_sigint(cmd: &mut std::process::Command) -> &mut std::process::Command {
    use std::os::unix::process::CommandExt;
    // SAFETY: between fork and exec the closure calls only signal(2), which
    // is async-signal-safe, and touches no memory of the parent.
    unsafe {
        cmd.pre_exec(|| {
            libc::signal(libc::SIGINT, libc::SIG_DFL);
            Ok(())
        })
    }
}

fn interrupt(child: &Child) {
    let ok = std::process::Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .expect("run kill");
    assert!(ok.success());
}

#[test]
#[cfg(target_os = "linux")]
fn ctrl_c_during_a_recorded_match_leaves_a_finished_recording() {
    let file = scratch("interrupt-match", "cut.mcap");
    let _ = std::fs::remove_file(&file);
    let child = naosoccer_cmd()
        .args(["match", "--seed", "3", "--minutes", "500", "--record"])
        .arg(&file)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    wait_for_handler(&child);
    interrupt(&child);
    let out = child.wait_with_output().unwrap();
    assert_eq!(out.status.code(), Some(130), "{}", text(&out));
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stdout.contains("final score"), "{stdout}");
    assert!(
        stderr.contains("interrupted") && stderr.contains("recording is finished"),
        "{stderr}"
    );
    // The recording is complete as a file (its summary written) and replays
    // identically as far as the match went.
    let replay = naosoccer(&["replay", file.to_str().unwrap()]);
    assert!(replay.status.success(), "{}", text(&replay));
    let said = String::from_utf8_lossy(&replay.stdout);
    assert!(said.contains("identical"), "{said}");
    assert!(!said.contains("truncated"), "{said}");
}

#[test]
#[cfg(target_os = "linux")]
fn ctrl_c_during_eval_reports_the_matches_played() {
    let child = naosoccer_cmd()
        .args([
            "eval",
            "--blue",
            "scripted",
            "--red",
            "random",
            "--matches",
            "100000",
            "--minutes",
            "0.2",
            "--threads",
            "1",
            "--json",
        ])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    wait_for_handler(&child);
    // Matches are played in blocks of 8; one block of 12-second matches
    // takes a small fraction of a CPU second, so after 2 CPU seconds several
    // are done, on any machine.
    wait_for_cpu_seconds(&child, 2.0);
    interrupt(&child);
    let out = child.wait_with_output().unwrap();
    assert_eq!(out.status.code(), Some(130), "{}", text(&out));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("eval stopped after"), "{stderr}");
    let played: usize = stderr
        .split("eval stopped after ")
        .nth(1)
        .and_then(|s| s.split_whitespace().next())
        .and_then(|n| n.parse().ok())
        .expect("a count of matches");
    assert!(played > 0, "{stderr}");
    let got: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(got["matches"], played);
    let n = played.to_string();
    let again = naosoccer(&[
        "eval",
        "--blue",
        "scripted",
        "--red",
        "random",
        "--matches",
        &n,
        "--minutes",
        "0.2",
        "--threads",
        "1",
        "--json",
    ]);
    let want: serde_json::Value = serde_json::from_slice(&again.stdout).unwrap();
    assert_eq!(got["results"], want["results"]);
}

#[test]
#[cfg(unix)]
fn a_closed_output_pipe_ends_eval_quietly() {
    let mut child = naosoccer_cmd()
        .args([
            "eval",
            "--blue",
            "scripted",
            "--red",
            "random",
            "--matches",
            "2",
            "--minutes",
            "0.1",
        ])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // Close the read end at once, as `head -0` would.
    drop(child.stdout.take());
    let mut err = String::new();
    child
        .stderr
        .take()
        .unwrap()
        .read_to_string(&mut err)
        .unwrap();
    let status = child.wait().unwrap();
    assert!(!err.contains("panicked"), "{err}");
    assert!(!err.contains("Broken pipe"), "{err}");
    use std::os::unix::process::ExitStatusExt;
    assert!(
        status.success() || status.signal() == Some(13),
        "{status:?} {err}"
    );
}

/// Ctrl-C during a recipe run's first stage, as a user stops a long run: the
/// process dies (training keeps no state in memory worth saving), and
/// `train --resume DIR` continues from the stage's last checkpoint to the
/// same final weights, byte for byte, as the run that was never stopped.
#[test]
#[cfg(all(target_os = "linux", feature = "train"))]
fn ctrl_c_during_a_recipe_run_resumes_to_the_same_team() {
    let recipe = scratch("interrupt-train", "recipe.toml");
    std::fs::write(
        &recipe,
        r#"description = "a stage long enough to stop, and a short one"
[[stage]]
name = "first"
algo = "ppo"
preset = "team"
minutes = 0.1
steps = 60000
matches = 4
rollout = 32
epochs = 1
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
epochs = 1
"#,
    )
    .unwrap();
    let run = |name: &str| {
        let dir = scratch("interrupt-train", name);
        let _ = std::fs::remove_dir_all(&dir);
        dir
    };
    let whole = run("whole");
    let out = naosoccer(&[
        "train",
        "--recipe",
        recipe.to_str().unwrap(),
        "--out",
        whole.to_str().unwrap(),
        "--seed",
        "4",
    ]);
    assert!(out.status.success(), "{}", text(&out));

    let cut = run("cut");
    let child = with_default_sigint(&mut naosoccer_cmd())
        .args(["train", "--recipe", recipe.to_str().unwrap(), "--out"])
        .arg(&cut)
        .args(["--seed", "4"])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    // Stopped once the first stage has a resumable checkpoint.
    let checkpoints = cut.join("01-first/checkpoints");
    loop {
        let resumable = std::fs::read_dir(&checkpoints).is_ok_and(|d| {
            d.flatten()
                .any(|e| e.file_name().to_string_lossy().ends_with(".resume.json"))
        });
        if resumable {
            break;
        }
        // Polling a condition, not timing it: the pause only spares the CPU.
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
    interrupt(&child);
    let status = child.wait_with_output().unwrap().status;
    assert!(!status.success(), "stopped by Ctrl-C: {status:?}");
    assert!(
        !cut.join("01-first/final.safetensors").exists(),
        "the first stage was stopped before its end"
    );
    let out = naosoccer(&["train", "--resume", cut.to_str().unwrap()]);
    assert!(out.status.success(), "{}", text(&out));
    assert!(
        text(&out).contains("continuing from its latest checkpoint"),
        "{}",
        text(&out)
    );
    assert!(
        std::fs::read(whole.join("final.safetensors")).unwrap()
            == std::fs::read(cut.join("final.safetensors")).unwrap(),
        "the resumed run's team differs from the uninterrupted one's"
    );
}
