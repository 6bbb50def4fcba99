//! End to end over TCP: a real server on an ephemeral port, real clients,
//! real matches; results compared with the same match played in process.

use crate::common;

use common::server::*;
use naosoccer_client::robot::{run_team, TeamRun};
use naosoccer_client::{Client, Push};
use naosoccer_policy::PolicyKind;
use naosoccer_proto::msg::{EndReason, ErrorCode, MatchId, Player, PlayerAction, Score};
use naosoccer_proto::{Action, Team, Tick, PLAYERS_PER_TEAM};

fn all_players() -> Vec<Player> {
    Player::all().collect()
}

fn team_run(addr: &str, team: Team, policy: PolicyKind, team_connection: bool) -> TeamRun {
    TeamRun {
        server: addr.to_owned(),
        team,
        token: if team == Team::Blue { BLUE } else { RED }.to_owned(),
        match_id: Some(MatchId(1)),
        players: all_players(),
        policy: policy.into(),
        team_connection,
    }
}

/// Eight robot clients, one per player, play a short lockstep match; the
/// result equals the in-process match with the same seed, config and policies.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn eight_robot_clients_match_the_in_process_runner() {
    let mut cfg = config(150);
    cfg.deadline_ms = 30_000; // no misses, however loaded the machine
    cfg.match_cfg.reward.progress = 1.0; // every reward term in play
    let match_cfg = cfg.match_cfg.clone();
    let server = start(cfg).await;
    let addr = server.addr();
    let blue = tokio::spawn({
        let run = team_run(&addr, Team::Blue, PolicyKind::Scripted, false);
        async move { run_team(&run).await }
    });
    let red = tokio::spawn({
        let run = team_run(&addr, Team::Red, PolicyKind::Random, false);
        async move { run_team(&run).await }
    });
    let blue = blue.await.unwrap().unwrap();
    let red = red.await.unwrap().unwrap();
    assert_eq!(blue.len() + red.len(), 8, "one connection per robot");

    // The same match in process (`naosoccer match`'s runner), summing each
    // robot's `Match::rewards` as it goes.
    let mut returns = [[0.0f32; PLAYERS_PER_TEAM]; 2];
    let out = naosoccer_eval::run::play_match(
        &match_cfg,
        42,
        &PolicyKind::Scripted,
        &PolicyKind::Random,
        |t| {
            for team in [Team::Blue, Team::Red] {
                for (ret, r) in returns[team.index()].iter_mut().zip(t.m.rewards(team)) {
                    *ret += r;
                }
            }
        },
    )
    .unwrap();
    let score = Score {
        blue: out.score.blue,
        red: out.score.red,
    };
    let hash = format!("{:016x}", out.state_hash);
    for r in blue.iter().chain(&red) {
        assert_eq!(r.end.reason, EndReason::Finished);
        assert_eq!(r.end.tick, Tick::new(out.ticks));
        assert_eq!(r.end.misses.blue, [0; 4]);
        assert_eq!(r.end.misses.red, [0; 4]);
        assert_eq!(r.end.score, score);
        assert_eq!(r.end.stats, out.stats, "same semantics through the socket");
        assert_eq!(r.end.state_hash, hash, "same final state, bit for bit");
    }

    // Each robot's return from the rewards the server sent equals its sum of
    // `Match::rewards` in process, bit for bit.
    for (team, results) in [(Team::Blue, &blue), (Team::Red, &red)] {
        for r in results {
            let p = r.players[0].index();
            assert_eq!(r.returns, [returns[team.index()][p]], "{team} robot {p}");
        }
    }
    assert!(
        returns.iter().flatten().any(|&r| r != 0.0),
        "the rewards are not all zero"
    );
    server.stop().await;
}

/// Same with one team connection per team, two matches at once on one server.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn team_connections_and_two_matches_at_once() {
    let mut cfg = config(80);
    cfg.deadline_ms = 30_000;
    cfg.matches = 2;
    let match_cfg = cfg.match_cfg.clone();
    let server = start(cfg).await;
    let addr = server.addr();
    let mut tasks = Vec::new();
    for id in [1, 2] {
        for team in Team::BOTH {
            let mut run = team_run(&addr, team, PolicyKind::Scripted, true);
            run.match_id = Some(MatchId(id));
            tasks.push(tokio::spawn(async move { run_team(&run).await }));
        }
    }
    for (i, t) in tasks.into_iter().enumerate() {
        let res = t.await.unwrap().unwrap();
        assert_eq!(res.len(), 1);
        let seed = 42 + i as u64 / 2; // match 2 gets seed + 1
        let (stats, score, _, hash) =
            in_process(&match_cfg, seed, PolicyKind::Scripted, PolicyKind::Scripted);
        assert_eq!(res[0].end.stats, stats);
        assert_eq!(res[0].end.score, score);
        assert_eq!(res[0].end.state_hash, hash);
    }
    server.stop().await;
}

/// Blue's team client answers a few ticks with `stay`, then drops its
/// connection. The match goes on to the end and blue's robots stand: the
/// result equals an in-process match with an idle blue team (the default
/// fill is the scripted policy, which would have played them otherwise).
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn client_disconnecting_mid_match_leaves_its_robots_standing() {
    let mut cfg = config(100);
    cfg.deadline_ms = 30_000;
    let match_cfg = cfg.match_cfg.clone();
    let server = start(cfg).await;
    let addr = server.addr();
    let red = tokio::spawn({
        let run = team_run(&addr, Team::Red, PolicyKind::Scripted, false);
        async move { run_team(&run).await }
    });
    let mut blue = Client::connect(addr.as_str(), "quitter").await.unwrap();
    blue.join(Some(MatchId(1)), Team::Blue, BLUE, &all_players())
        .await
        .unwrap();
    let stay: Vec<PlayerAction> = all_players()
        .into_iter()
        .map(|player| PlayerAction {
            player,
            action: Action::Stay,
        })
        .collect();
    for expected in 0..5u64 {
        match blue.next_push().await.unwrap() {
            Push::Observation(o) => {
                assert_eq!(o.tick, Tick::new(expected));
                assert_eq!(o.observations.len(), PLAYERS_PER_TEAM);
                blue.send_actions(o.tick, &stay).await.unwrap();
            }
            other => panic!("expected an observation, got {other:?}"),
        }
    }
    drop(blue);

    let red = red.await.unwrap().unwrap();
    let (stats, score, ticks, hash) =
        in_process(&match_cfg, 42, PolicyKind::Idle, PolicyKind::Scripted);
    for r in &red {
        assert_eq!(r.end.reason, EndReason::Finished);
        assert_eq!(r.end.tick, Tick::new(ticks));
        assert_eq!(r.end.stats, stats);
        assert_eq!(r.end.score, score);
        assert_eq!(r.end.state_hash, hash, "blue's robots stood");
    }
    server.stop().await;
}

/// Blue joins and never answers. Each tick waits for the deadline, then
/// plays blue's robots as `stay` and counts a miss; red keeps playing, and
/// the server keeps answering other connections meanwhile.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn silent_client_misses_deadlines_and_the_match_goes_on() {
    let ticks = 12;
    let mut cfg = config(ticks);
    cfg.deadline_ms = 250;
    let match_cfg = cfg.match_cfg.clone();
    let server = start(cfg).await;
    let addr = server.addr();
    let mut silent = Client::connect(addr.as_str(), "silent").await.unwrap();
    silent
        .join(Some(MatchId(1)), Team::Blue, BLUE, &all_players())
        .await
        .unwrap();
    let red = tokio::spawn({
        let run = team_run(&addr, Team::Red, PolicyKind::Scripted, false);
        async move { run_team(&run).await }
    });
    let mut other = Client::connect(addr.as_str(), "bystander").await.unwrap();
    assert_eq!(other.ping(7).await.unwrap(), 7);

    let red = red.await.unwrap().unwrap();
    let (stats, _, total, hash) =
        in_process(&match_cfg, 42, PolicyKind::Idle, PolicyKind::Scripted);
    for r in &red {
        assert_eq!(r.end.tick, Tick::new(total));
        assert_eq!(r.end.misses.blue, [total; 4], "every blue tick missed");
        assert_eq!(r.end.misses.red, [0; 4]);
        assert_eq!(r.end.stats, stats, "missed ticks are played as stay");
        assert_eq!(r.end.state_hash, hash);
    }
    // The silent client still gets its observations and the match end.
    let mut seen = 0;
    loop {
        match silent.next_push().await.unwrap() {
            Push::Observation(_) => seen += 1,
            Push::MatchEnd(end) => {
                assert_eq!(end.misses.blue, [total; 4]);
                break;
            }
            Push::Error(e) => panic!("unexpected {e}"),
        }
    }
    assert_eq!(seen, total);
    // After the match end the connection is back in the lobby.
    assert_eq!(silent.ping(1).await.unwrap(), 1);
    server.stop().await;
}

/// A late lockstep action is answered `deadline_exceeded`, not applied.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn late_action_is_deadline_exceeded() {
    let mut cfg = config(40);
    cfg.deadline_ms = 50;
    cfg.start_players = 1;
    cfg.fill = naosoccer_proto::msg::Fill::Idle;
    let server = start(cfg).await;
    let mut c = Client::connect(server.addr().as_str(), "late")
        .await
        .unwrap();
    let p0 = Player::new(0).unwrap();
    c.join(Some(MatchId(1)), Team::Blue, BLUE, &[p0])
        .await
        .unwrap();
    // Wait (by not answering) until tick 2 is observed, then answer tick 0.
    loop {
        match c.next_push().await.unwrap() {
            Push::Observation(o) if o.tick >= Tick::new(2) => break,
            Push::Observation(_) => {}
            other => panic!("{other:?}"),
        }
    }
    c.send_actions(
        Tick::ZERO,
        &[PlayerAction {
            player: p0,
            action: Action::Forward,
        }],
    )
    .await
    .unwrap();
    loop {
        match c.next_push().await.unwrap() {
            Push::Error(e) => {
                assert_eq!(e.code, ErrorCode::DeadlineExceeded);
                assert_eq!(e.in_reply_to.as_deref(), Some("action"));
                assert_eq!(e.tick, Some(Tick::ZERO));
                assert!(!e.fatal);
                break;
            }
            Push::Observation(_) => {}
            Push::MatchEnd(_) => panic!("match ended before the late action was refused"),
        }
    }
    server.stop().await;
}

/// Shutdown while a match runs: the client gets `match_end` (reason
/// shutdown), then a fatal `unavailable`, and `run` returns.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn graceful_shutdown_ends_matches_and_tells_clients() {
    let mut cfg = config(100_000);
    cfg.start_players = 1;
    let server = start(cfg).await;
    let mut c = Client::connect(server.addr().as_str(), "stayer")
        .await
        .unwrap();
    let mut lobby = Client::connect(server.addr().as_str(), "lobby")
        .await
        .unwrap();
    c.join(None, Team::Red, RED, &[Player::new(2).unwrap()])
        .await
        .unwrap();
    match c.next_push().await.unwrap() {
        Push::Observation(o) => assert_eq!(o.tick, Tick::ZERO),
        other => panic!("{other:?}"),
    }
    // Not answering: the tick waits for us (deadline 1 s), so shutdown lands mid-match.
    let stopper = tokio::spawn(server.stop());
    let end = loop {
        match c.next_push().await.unwrap() {
            Push::MatchEnd(end) => break end,
            Push::Observation(_) => {}
            Push::Error(e) => panic!("{e}"),
        }
    };
    assert_eq!(end.reason, EndReason::Shutdown);
    match c.recv().await.unwrap() {
        naosoccer_proto::msg::ServerMsg::Error(e) => {
            assert_eq!(e.code, ErrorCode::Unavailable);
            assert!(e.fatal);
        }
        other => panic!("{other:?}"),
    }
    match lobby.recv().await.unwrap() {
        naosoccer_proto::msg::ServerMsg::Error(e) => assert_eq!(e.code, ErrorCode::Unavailable),
        other => panic!("{other:?}"),
    }
    stopper.await.unwrap();
}

/// Real time: ticks advance on the clock whether or not clients answer; a
/// client that answers every observation promptly has no misses, a robot
/// nobody controls is filled, and the match ends on time.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn realtime_match_runs_on_the_clock() {
    let ticks = 15;
    let mut cfg = config(ticks);
    cfg.mode = naosoccer_proto::msg::Mode::Realtime;
    cfg.start_players = 4;
    let server = start(cfg).await;
    let run = team_run(&server.addr(), Team::Blue, PolicyKind::Scripted, true);
    let started = std::time::Instant::now();
    let res = run_team(&run).await.unwrap();
    let elapsed = started.elapsed();
    let end = &res[0].end;
    assert_eq!(end.reason, EndReason::Finished);
    assert_eq!(end.tick, Tick::new(u64::from(ticks)));
    // 15 ticks at 10 Hz: at least 1.4 s of wall-clock time.
    assert!(
        elapsed >= std::time::Duration::from_millis(1400),
        "{elapsed:?}"
    );
    server.stop().await;
}

/// The Python client printed in docs/PROTOCOL.md, run as written (standard
/// library only) against a real server, plays a whole match.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn documented_python_client_plays_a_match() {
    let doc = include_str!("../../docs/PROTOCOL.md");
    let at = doc.find("```python\n").expect("python block") + "```python\n".len();
    let script = &doc[at..at + doc[at..].find("```").unwrap()];
    let mut cfg = config(30);
    cfg.start_players = 1;
    let server = start(cfg).await;
    let script = script
        .replace("BLUE_TOKEN", BLUE)
        .replace("7878", &server.addr.port().to_string());
    let out = tokio::task::spawn_blocking(move || {
        std::process::Command::new("python3")
            .arg("-c")
            .arg(&script)
            .output()
            .expect("python3 runs")
    })
    .await
    .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{stdout}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(stdout.contains("'type': 'welcome'"), "{stdout}");
    assert!(stdout.contains("final score"), "{stdout}");
    server.stop().await;
}
