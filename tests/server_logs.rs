//! Team tokens stay secret (issue 6): no token, right or guessed, appears
//! in an error message or a log line. A test binary of its own, because it
//! captures the logs with a global subscriber: with a thread-local one, a
//! test running beside it on another thread could cache the server's log
//! call sites as disabled, and the capture then missed lines (two runs in
//! ten under load).

mod common;

use common::server::*;
use naosoccer_client::{Client, Push};
use naosoccer_proto::msg::{ActionMsg, ClientMsg, CreateMatch, EndReason, ErrorCode, MatchId};
use naosoccer_proto::Team;
use std::sync::{Arc, Mutex};

/// Team tokens are bound to their team and cannot create matches; no token
/// (right or guessed) appears in any error message or log line.
#[tokio::test]
async fn tokens_are_team_bound_and_never_echoed_or_logged() {
    let logs = Arc::new(Mutex::new(Vec::<u8>::new()));
    let sink = logs.clone();
    let subscriber = tracing_subscriber::fmt()
        .with_max_level(tracing::Level::TRACE)
        .with_ansi(false)
        .with_writer(move || LogSink(sink.clone()))
        .finish();
    // The only test of this binary: a global subscriber sees every thread.
    tracing::subscriber::set_global_default(subscriber).unwrap();

    const GUESS: &str = "guessed-token-0123";
    let mut cfg = config(10);
    cfg.start_players = 1;
    let server = start(cfg).await;
    let mut c = Client::connect(server.addr(), "sneaky").await.unwrap();
    let mut errors = Vec::new();
    for (team, token) in [(Team::Red, BLUE), (Team::Blue, RED), (Team::Blue, GUESS)] {
        let e = c
            .join(Some(MatchId(1)), team, token, &[p(0)])
            .await
            .unwrap_err();
        assert_eq!(e.code(), Some(ErrorCode::PermissionDenied), "{e}");
        errors.push(e.to_string());
    }
    for token in [BLUE, RED, GUESS] {
        let e = c
            .create_match(CreateMatch {
                token: token.into(),
                ..Default::default()
            })
            .await
            .unwrap_err();
        assert_eq!(e.code(), Some(ErrorCode::PermissionDenied), "{e}");
        errors.push(e.to_string());
    }
    let joined = c
        .join(Some(MatchId(1)), Team::Blue, BLUE, &[p(0)])
        .await
        .unwrap();
    // A blue connection acting for red.
    let first = match c.next_push().await.unwrap() {
        Push::Observation(o) => o,
        other => panic!("{other:?}"),
    };
    c.send(&ClientMsg::Action(ActionMsg {
        tick: first.tick,
        team: Some(Team::Red),
        actions: stay(&[p(0)]),
    }))
    .await
    .unwrap();
    match c.next_push().await.unwrap() {
        Push::Error(e) => {
            assert_eq!(e.code, ErrorCode::PermissionDenied, "{e}");
            errors.push(e.to_string());
        }
        other => panic!("{other:?}"),
    }
    c.send_actions(first.tick, &stay(&joined.players))
        .await
        .unwrap();
    let (end, more) = play_out(&mut c, &joined.players).await;
    assert_eq!(end.reason, EndReason::Finished);
    errors.extend(more.iter().map(|e| e.to_string()));
    server.stop().await;

    let logs = String::from_utf8(logs.lock().unwrap().clone()).unwrap();
    assert!(logs.contains("joined"), "the capture works: {logs}");
    for secret in [BLUE, RED, ADMIN, GUESS] {
        assert!(!logs.contains(secret), "{secret} logged:\n{logs}");
        for e in &errors {
            assert!(!e.contains(secret), "{secret} echoed: {e}");
        }
    }
}

struct LogSink(Arc<Mutex<Vec<u8>>>);

impl std::io::Write for LogSink {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        self.0.lock().unwrap().extend_from_slice(buf);
        Ok(buf.len())
    }
    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}
