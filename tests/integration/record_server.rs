//! A match played through the server in lockstep is recorded to MCAP and
//! the recording replays identically, with the statistics the clients saw.

use crate::common;

use common::server::*;
use naosoccer_client::robot::{run_team, TeamRun};
use naosoccer_policy::PolicyKind;
use naosoccer_proto::msg::{EndReason, MatchId, Player};
use naosoccer_proto::Team;
use naosoccer_record::{replay, Recording, ReplayOutcome};

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn server_match_is_recorded_and_replays_identically() {
    let dir = std::env::temp_dir().join(format!("naosoccer-record-server-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let mut cfg = config(120);
    cfg.deadline_ms = 30_000;
    cfg.record_dir = Some(dir.clone());
    let server = start(cfg).await;
    let addr = server.addr();
    let mut tasks = Vec::new();
    for (team, policy) in [
        (Team::Blue, PolicyKind::Scripted),
        (Team::Red, PolicyKind::Random),
    ] {
        let run = TeamRun {
            server: addr.clone(),
            team,
            token: if team == Team::Blue { BLUE } else { RED }.to_owned(),
            match_id: Some(MatchId(1)),
            players: Player::all().collect(),
            policy: policy.into(),
            team_connection: true,
        };
        tasks.push(tokio::spawn(async move { run_team(&run).await }));
    }
    let mut ends = Vec::new();
    for t in tasks {
        ends.extend(t.await.unwrap().unwrap());
    }
    server.stop().await;

    let path = dir.join("match-1-seed-42.mcap");
    let rec = Recording::read_file(&path).unwrap();
    assert!(rec.is_complete(), "{:?}", rec.truncated);
    assert_eq!(rec.meta.source, "server");
    assert_eq!(rec.meta.match_id, Some(1));
    assert_eq!(rec.meta.mode.as_deref(), Some("lockstep"));
    let fin = rec.stats.clone().unwrap();
    for e in &ends {
        assert_eq!(e.end.reason, EndReason::Finished);
        assert_eq!(
            e.end.stats, fin.stats,
            "the recording has the clients' statistics"
        );
        assert_eq!(e.end.state_hash, fin.state_hash);
    }
    assert_eq!(rec.actions.len(), 120);
    match replay(&rec).unwrap() {
        ReplayOutcome::Identical { ticks, truncated } => {
            assert_eq!(ticks, 120);
            assert!(!truncated);
        }
        other => panic!("server recording does not replay: {other:?}"),
    }
    std::fs::remove_dir_all(&dir).unwrap();
}
