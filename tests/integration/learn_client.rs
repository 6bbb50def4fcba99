//! A trained team plays over the socket: `naosoccer client --policy ppo:DIR`
//! (the real binary, which links no libtorch) joins a real server as blue,
//! the scripted team plays red, and the match equals the same match played
//! in process with the same networks, bit for bit.

use crate::common;

use std::path::PathBuf;
use std::process::Command;

use common::naosoccer;
use common::server::*;
use naosoccer_client::robot::{run_team, TeamRun};
use naosoccer_eval::run::{play_one, Fixture, MatchOutcome, Side};
use naosoccer_policy::{LearnedPolicy, PolicyKind};
use naosoccer_proto::msg::{EndReason, MatchEnd, MatchId, Player};
use naosoccer_proto::{Team, Tick};
use naosoccer_referee::{Match, MatchConfig};

/// A shipped trained team (a sampling PPO team: its draws are keyed by the
/// match seed, so both matches draw alike).
fn shipped_run() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("assets/policies/ppo-paper-seed1")
}

/// The match in process (`naosoccer match`'s runner): `spec`'s trained
/// team blue, the scripted team red; `on_tick` sees the match after every
/// tick.
fn trained_blue_in_process(
    spec: &str,
    cfg: &MatchConfig,
    seed: u64,
    mut on_tick: impl FnMut(&Match),
) -> MatchOutcome {
    let mut blue = Side::Learned(Box::new(LearnedPolicy::load(spec).unwrap()));
    let mut red = Side::Builtin(PolicyKind::Scripted);
    play_one(cfg, &mut blue, &mut red, Fixture::kick_off(seed), |t| {
        on_tick(t.m);
        std::ops::ControlFlow::Continue(())
    })
    .unwrap()
}

/// The match a client saw end is the in-process one, bit for bit.
fn assert_same_match(end: &MatchEnd, out: &MatchOutcome) {
    assert_eq!(end.tick, Tick::new(out.ticks));
    assert_eq!(end.score, out.score);
    assert_eq!(end.stats, out.stats, "same semantics through the socket");
    assert_eq!(
        end.state_hash,
        format!("{:016x}", out.state_hash),
        "same final state, bit for bit"
    );
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn trained_team_plays_over_the_socket_as_in_process() {
    let run = shipped_run();
    let spec = format!("ppo:{}", run.display());

    let mut cfg = config(100);
    cfg.deadline_ms = 30_000; // no misses, however loaded the machine
    let match_cfg = cfg.match_cfg.clone();
    let server = start(cfg).await;
    let addr = server.addr();

    // Blue: the binary, one robot connection per player (like real robots).
    let blue = tokio::task::spawn_blocking({
        let (addr, spec) = (addr.clone(), spec.clone());
        move || {
            naosoccer(&[
                "client", "--server", &addr, "--team", "blue", "--token", BLUE, "--match", "1",
                "--policy", &spec,
            ])
        }
    });
    let red = tokio::spawn({
        let run = TeamRun {
            server: addr.clone(),
            team: Team::Red,
            token: RED.to_owned(),
            match_id: Some(MatchId(1)),
            players: Player::all().collect(),
            policy: PolicyKind::Scripted.into(),
            team_connection: true,
        };
        async move { run_team(&run).await }
    });
    let blue = blue.await.unwrap();
    let red = red.await.unwrap().unwrap();
    let stdout = String::from_utf8_lossy(&blue.stdout);
    assert!(
        blue.status.success(),
        "client failed: {}\n{stdout}",
        String::from_utf8_lossy(&blue.stderr)
    );
    let end = &red[0].end;
    assert_eq!(end.reason, EndReason::Finished);
    assert_eq!(
        end.misses.blue, [0; 4],
        "the trained team answered every tick"
    );
    assert!(
        stdout.contains(&format!("blue {} - {} red", end.score.blue, end.score.red)),
        "the client reports the final score: {stdout}"
    );
    assert!(stdout.contains("blue: goals"), "{stdout}");

    // The same match in process: the same networks for blue, scripted red.
    let mut returns = [0.0f32; 4];
    let out = trained_blue_in_process(&spec, &match_cfg, 42, |m| {
        for (ret, r) in returns.iter_mut().zip(m.rewards(Team::Blue)) {
            *ret += r;
        }
    });
    // The client prints each robot's return from the rewards it was sent.
    let printed: Vec<String> = returns
        .iter()
        .enumerate()
        .map(|(p, r)| format!("robot {p} {r:.2}"))
        .collect();
    assert!(
        stdout.contains(&format!(
            "blue: return (sum of the match configuration's reward): {}",
            printed.join(", ")
        )),
        "{stdout}"
    );
    assert_same_match(end, &out);
    server.stop().await;
}

#[test]
fn bad_policy_specs_fail_before_joining() {
    let out = naosoccer(&[
        "client",
        "--team",
        "blue",
        "--token",
        "x",
        "--server",
        "127.0.0.1:9",
        "--policy",
        "ppo:/nonexistent-run-dir",
    ]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("loading --policy ppo:/nonexistent-run-dir"),
        "{err}"
    );

    let out = naosoccer(&[
        "client", "--team", "blue", "--token", "x", "--policy", "greedy",
    ]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("unknown policy \"greedy\"") && err.contains("ppo:DIR"),
        "{err}"
    );
}

/// `naosoccer server --fill ppo:DIR` (the real binary): a trained team plays
/// the slots nobody joined. Red joins over a team connection with the
/// scripted policy; blue is the server's trained fill; the match equals the
/// same match in process, bit for bit.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_server_fills_empty_slots_with_a_trained_team() {
    use std::io::BufRead;
    use std::process::Stdio;

    let spec = format!("ppo:{}", shipped_run().display());
    let rec_dir = std::env::temp_dir().join(format!("naosoccer-fill-rec-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&rec_dir);
    let mut server = Command::new(env!("CARGO_BIN_EXE_naosoccer"))
        .args([
            "server",
            "--port",
            "0",
            "--seed",
            "9",
            "--minutes",
            "0.25",
            "--fill",
            &spec,
            "--start-players",
            "4",
            "--exit-when-done",
            "--record-dir",
            rec_dir.to_str().unwrap(),
            "--blue-token",
            BLUE,
            "--red-token",
            RED,
            "--admin-token",
            ADMIN,
        ])
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .expect("start the server");
    let stdout = server.stdout.take().unwrap();
    let addr = tokio::task::spawn_blocking(move || {
        let mut line = String::new();
        std::io::BufReader::new(stdout)
            .read_line(&mut line)
            .unwrap();
        // "naosoccer server on 127.0.0.1:PORT (lockstep mode, 1 match(es))"
        line.split_whitespace().nth(3).unwrap().to_owned()
    })
    .await
    .unwrap();
    // The match says who fills its slots: the trained team, not `fill`.
    let mut admin = naosoccer_client::Client::connect(&addr, "admin")
        .await
        .unwrap();
    let listed = admin.list_matches().await.unwrap();
    assert_eq!(listed[0].fill_team.as_deref(), Some(spec.as_str()));
    drop(admin);
    let red = run_team(&TeamRun {
        server: addr,
        team: Team::Red,
        token: RED.to_owned(),
        match_id: Some(MatchId(1)),
        players: Player::all().collect(),
        policy: PolicyKind::Scripted.into(),
        team_connection: true,
    })
    .await
    .unwrap();
    let status = tokio::task::spawn_blocking(move || server.wait().unwrap())
        .await
        .unwrap();
    assert!(
        status.success(),
        "the server exits 0 when its match is done"
    );
    let end = &red[0].end;
    assert_eq!(end.reason, EndReason::Finished);

    let match_cfg = MatchConfig {
        minutes: 0.25,
        ..Default::default()
    };
    let out = trained_blue_in_process(&spec, &match_cfg, 9, |_| {});
    assert_same_match(end, &out);
    let rec = naosoccer_record::Recording::read_file(&rec_dir.join("match-1-seed-9.mcap")).unwrap();
    let players = format!("clients, empty slots {spec}");
    assert_eq!(
        (rec.meta.blue.as_str(), rec.meta.red.as_str()),
        (players.as_str(), players.as_str())
    );
    std::fs::remove_dir_all(&rec_dir).unwrap();

    let out = naosoccer(&[
        "server",
        "--port",
        "0",
        "--fill",
        "ppo:/nonexistent-run-dir",
    ]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("loading --fill ppo:/nonexistent-run-dir"),
        "{err}"
    );
}
