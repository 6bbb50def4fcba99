//! The server under bad peers, faults and hostile input (issue 6): every
//! limit answers with its documented error, slow and dead peers are dropped
//! without stalling anyone, tokens stay secret and team-bound, a panicking
//! match ends alone. All on 127.0.0.1; waits are on events or tokio's paused
//! clock, never on sleeps.

use crate::common;

use common::server::*;
use naosoccer_client::{Client, ClientError, Push};
use naosoccer_proto::msg::{
    ClientMsg, CreateMatch, EndReason, ErrorCode, ErrorMsg, Hello, MatchEnd, MatchId, MatchInfo,
    MatchState, Player, ServerMsg,
};
use naosoccer_proto::{frame, Team, Tick};
use naosoccer_referee::Match;
use naosoccer_server::{Hooks, MatchObserver, ServerConfig, ServerError, TickRecord};
use std::net::SocketAddr;
use std::sync::{Arc, Mutex};
use tokio::net::{TcpListener, TcpSocket, TcpStream};
use tokio::sync::oneshot;

fn all_players() -> Vec<Player> {
    Player::all().collect()
}

async fn expect_error(c: &mut Client, code: ErrorCode, fatal: bool) -> ErrorMsg {
    match c.recv().await {
        Ok(ServerMsg::Error(e)) => {
            assert_eq!(e.code, code, "{e}");
            assert_eq!(e.fatal, fatal, "{e}");
            e
        }
        other => panic!("expected a {code} error, got {other:?}"),
    }
}

async fn expect_closed(c: &mut Client) {
    let r = c.recv().await;
    assert!(matches!(r, Err(ClientError::Closed)), "{r:?}");
}

/// A connection from a chosen loopback source address (Linux routes all of
/// 127.0.0.0/8 to lo, so 127.0.0.2 is a second "machine").
async fn connect_from(src: &str, server: SocketAddr) -> Result<Client, ClientError> {
    let sock = TcpSocket::new_v4().unwrap();
    sock.bind(format!("{src}:0").parse().unwrap()).unwrap();
    let stream = sock.connect(server).await.unwrap();
    Client::handshake(stream, &Hello::new("test")).await
}

fn refused(r: Result<Client, ClientError>, limit: &str) {
    match r {
        Err(ClientError::Server(e)) => {
            assert_eq!(e.code, ErrorCode::ResourceExhausted, "{e}");
            assert!(e.fatal, "{e}");
            assert!(e.message.contains(limit), "{e}");
        }
        Err(other) => panic!("expected resource_exhausted ({limit}), got {other}"),
        Ok(_) => panic!("expected resource_exhausted ({limit}), got a welcome"),
    }
}

#[tokio::test]
async fn connections_are_limited_in_total_and_per_address() {
    let mut cfg = config(10);
    cfg.max_connections = 3;
    cfg.limits.max_connections_per_addr = 2;
    let server = start(cfg).await;
    let mut a = connect_from("127.0.0.1", server.addr).await.unwrap();
    let _b = connect_from("127.0.0.1", server.addr).await.unwrap();
    refused(
        connect_from("127.0.0.1", server.addr).await,
        "max_connections_per_addr",
    );
    // Another address still gets in, up to the total.
    let mut c = connect_from("127.0.0.2", server.addr).await.unwrap();
    refused(
        connect_from("127.0.0.3", server.addr).await,
        "max_connections",
    );
    assert_eq!(a.ping(1).await.unwrap(), 1);
    assert_eq!(c.ping(2).await.unwrap(), 2);
    server.stop().await;
}

#[tokio::test]
async fn joins_per_connection_are_limited() {
    let mut cfg = config(10);
    cfg.limits.max_joins_per_connection = 2;
    let server = start(cfg).await;
    let mut c = Client::connect(server.addr(), "rejoiner").await.unwrap();
    for _ in 0..2 {
        c.join(Some(MatchId(1)), Team::Blue, BLUE, &[p(0)])
            .await
            .unwrap();
        assert_eq!(c.leave().await.unwrap(), MatchId(1));
    }
    let e = c
        .join(Some(MatchId(1)), Team::Blue, BLUE, &[p(0)])
        .await
        .unwrap_err();
    assert_eq!(e.code(), Some(ErrorCode::ResourceExhausted), "{e}");
    assert_eq!(c.ping(7).await.unwrap(), 7, "not fatal");
    // A new connection may join again.
    let mut d = Client::connect(server.addr(), "fresh").await.unwrap();
    d.join(Some(MatchId(1)), Team::Blue, BLUE, &[p(0)])
        .await
        .unwrap();
    server.stop().await;
}

/// One message a second with a burst of 5 (hello takes one): four pings pass,
/// then messages are refused without closing; a peer that sends another
/// burst's worth while refused is disconnected. The test takes milliseconds,
/// far less than the one second a new token needs.
#[tokio::test]
async fn message_rate_is_limited_by_a_token_bucket() {
    let mut cfg = config(10);
    cfg.limits.messages_per_second = 1;
    cfg.limits.message_burst = 5;
    let server = start(cfg).await;
    let mut c = Client::connect(server.addr(), "flooder").await.unwrap();
    for n in 0..4 {
        assert_eq!(c.ping(n).await.unwrap(), n);
    }
    let e = c.ping(4).await.unwrap_err();
    assert_eq!(e.code(), Some(ErrorCode::ResourceExhausted), "{e}");
    let ClientError::Server(e) = e else { panic!() };
    assert!(!e.fatal && e.message.contains("messages_per_second"), "{e}");
    assert_eq!(
        e.in_reply_to.as_deref(),
        Some("ping"),
        "pairable (issue 15)"
    );
    let mut flood = Vec::new();
    for nonce in 0..5 {
        let msg = ClientMsg::Ping(naosoccer_proto::msg::Ping { nonce });
        flood.extend(frame::encode(&msg).unwrap());
    }
    c.send_raw(&flood).await.unwrap();
    for _ in 0..4 {
        let e = expect_error(&mut c, ErrorCode::ResourceExhausted, false).await;
        assert_eq!(e.in_reply_to.as_deref(), Some("ping"));
    }
    let e = expect_error(&mut c, ErrorCode::ResourceExhausted, true).await;
    assert_eq!(e.in_reply_to.as_deref(), Some("ping"));
    expect_closed(&mut c).await;
    let mut other = Client::connect(server.addr(), "neighbour").await.unwrap();
    assert_eq!(other.ping(1).await.unwrap(), 1);
    server.stop().await;
}

/// Half a frame, then nothing: closed with `deadline_exceeded` once the
/// frame deadline passes (paused clock; the server is real).
#[tokio::test(start_paused = true)]
async fn half_a_frame_is_closed_after_the_frame_timeout() {
    let mut cfg = config(10);
    cfg.limits.frame_timeout_ms = 5_000;
    let server = start(cfg).await;
    let mut c = Client::connect(server.addr(), "stutter").await.unwrap();
    let start = tokio::time::Instant::now();
    let mut half = 100u32.to_be_bytes().to_vec();
    half.extend_from_slice(br#"{"type":"pi"#);
    c.send_raw(&half).await.unwrap();
    let e = expect_error(&mut c, ErrorCode::DeadlineExceeded, true).await;
    assert!(e.message.contains("frame_timeout_ms"), "{e}");
    let waited = start.elapsed();
    assert!(
        waited >= std::time::Duration::from_secs(5) && waited <= std::time::Duration::from_secs(11),
        "{waited:?}"
    );
    expect_closed(&mut c).await;
    server.stop().await;
}

/// Greeted, then silent: closed after the idle timeout.
#[tokio::test(start_paused = true)]
async fn idle_connection_is_closed_after_the_idle_timeout() {
    let mut cfg = config(10);
    cfg.limits.idle_timeout_ms = 30_000;
    let server = start(cfg).await;
    let mut c = Client::connect(server.addr(), "sleeper").await.unwrap();
    let start = tokio::time::Instant::now();
    let e = expect_error(&mut c, ErrorCode::DeadlineExceeded, true).await;
    assert!(e.message.contains("idle_timeout_ms"), "{e}");
    assert!(start.elapsed() >= std::time::Duration::from_secs(30));
    expect_closed(&mut c).await;
    server.stop().await;
}

/// A robot client joins and then never reads. The server does not buffer
/// for it without bound: once its queue (`max_outbound`) is full the match
/// drops it (its robot stands, its slot is free again) and the write
/// deadline closes the connection. Meanwhile another match plays to its end,
/// and afterwards a new client takes the dropped robot back.
#[tokio::test(start_paused = true)]
async fn client_that_stops_reading_is_dropped_and_others_play_on() {
    let mut cfg = config(100_000);
    cfg.start_players = 5;
    cfg.deadline_ms = 1;
    cfg.limits.max_outbound = 8;
    cfg.limits.messages_per_second = 1_000_000_000;
    cfg.limits.message_burst = 1_000_000_000;
    let server = start(cfg).await;

    // Small receive buffer so the kernel holds little on the reader's behalf.
    let sock = TcpSocket::new_v4().unwrap();
    sock.set_recv_buffer_size(4096).unwrap();
    let stream = sock.connect(server.addr).await.unwrap();
    let mut slow = Client::handshake(stream, &Hello::new("slow"))
        .await
        .unwrap();
    slow.join(Some(MatchId(1)), Team::Blue, BLUE, &all_players())
        .await
        .unwrap();
    // A well-behaved robot client in the same match.
    let mut keeper = join_robot(&server, "keeper", Team::Red, RED, p(0)).await;
    let keeper = tokio::spawn(async move { play_out(&mut keeper, &[p(0)]).await });

    let mut admin = Client::connect(server.addr(), "admin").await.unwrap();
    let other = admin
        .create_match(CreateMatch {
            token: ADMIN.into(),
            minutes: Some(0.25),
            start_players: Some(4),
            ..Default::default()
        })
        .await
        .unwrap();
    let mut good = Client::connect(server.addr(), "good").await.unwrap();
    let joined = good
        .join(Some(other.match_id), Team::Blue, BLUE, &all_players())
        .await
        .unwrap();
    let (end, errors) = play_out(&mut good, &joined.players).await;
    assert_eq!(end.reason, EndReason::Finished);
    assert_eq!(end.tick, Tick::new(joined.total_ticks));
    assert!(errors.is_empty(), "{errors:?}");

    // The slow match advances a tick per deadline of the paused clock:
    // drive the clock a deadline at a time and look now and then until the
    // server has dropped the slow client.
    let mut dropped_at = None;
    for i in 0..1_000_000u32 {
        tokio::time::advance(std::time::Duration::from_millis(1)).await;
        if i % 64 != 0 {
            continue;
        }
        let info = match_info(&mut admin, MatchId(1)).await;
        assert_eq!(info.state, MatchState::Running, "never dropped");
        if !info.taken.blue[0] {
            dropped_at = Some(info.tick);
            break;
        }
    }
    let dropped_at = dropped_at.expect("the slow client was never dropped");

    // The robots stand and the slot is free: a new client takes them back.
    let mut back = Client::connect(server.addr(), "back").await.unwrap();
    back.join(Some(MatchId(1)), Team::Blue, BLUE, &all_players())
        .await
        .unwrap();
    for _ in 0..3 {
        match back.next_push().await.unwrap() {
            Push::Observation(o) => {
                assert!(o.tick >= dropped_at);
                back.send_actions(o.tick, &stay(&all_players()))
                    .await
                    .unwrap()
            }
            other => panic!("{other:?}"),
        }
    }
    back.leave().await.unwrap();

    // Now read what the slow client was sent: a bounded number of
    // observations, then the end of the connection.
    let mut observations = 0u64;
    let last = loop {
        match slow.recv().await {
            Ok(ServerMsg::Observation(_)) => observations += 1,
            other => break other,
        }
    };
    match &last {
        Err(ClientError::Closed | ClientError::Wire(_)) => {}
        Ok(ServerMsg::Error(e)) => assert_eq!(e.code, ErrorCode::ResourceExhausted, "{e}"),
        other => panic!("unexpected {other:?}"),
    }
    assert!(
        observations <= dropped_at.get(),
        "{observations} observations, dropped at tick {dropped_at}"
    );
    server.stop().await;
    let (end, errors) = keeper.await.unwrap();
    assert!(errors.is_empty(), "{errors:?}");
    assert!(end.tick > dropped_at);
    assert_eq!(end.misses.red[0], 0, "the keeper was never kept waiting");
}

/// Polls match 1 until blue player 0's slot is free again (the server has
/// noticed its client's disconnect).
async fn wait_until_blue_0_is_free(c: &mut Client) {
    for _ in 0..10_000 {
        if !match_info(c, MatchId(1)).await.taken.blue[0] {
            return;
        }
    }
    panic!("the disconnected client's slot never became free");
}

async fn match_info(c: &mut Client, id: MatchId) -> MatchInfo {
    c.list_matches()
        .await
        .unwrap()
        .into_iter()
        .find(|m| m.match_id == id)
        .expect("match listed")
}

/// A robot client that loses its connection mid-match reconnects with its
/// token and takes its robot back; the match waits for it again and ends
/// normally for everyone.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn reconnecting_robot_client_takes_its_robot_back() {
    let mut cfg = config(40);
    cfg.start_players = 2;
    cfg.deadline_ms = 60_000;
    let server = start(cfg).await;
    let mut keeper = join_robot(&server, "keeper", Team::Blue, BLUE, p(1)).await;
    let mut first = join_robot(&server, "robot-0", Team::Blue, BLUE, p(0)).await;
    for tick in 0..5u64 {
        for (c, pl) in [(&mut keeper, p(1)), (&mut first, p(0))] {
            match c.next_push().await.unwrap() {
                Push::Observation(o) => {
                    assert_eq!(o.tick, Tick::new(tick));
                    c.send_actions(o.tick, &stay(&[pl])).await.unwrap();
                }
                other => panic!("{other:?}"),
            }
        }
    }
    drop(first);
    // The keeper has not answered tick 5, so the match waits at tick 5
    // while the server notices the disconnect; wait for its slot to free.
    let mut again = Client::connect(server.addr(), "robot-0 again")
        .await
        .unwrap();
    wait_until_blue_0_is_free(&mut again).await;
    let joined = again
        .join(Some(MatchId(1)), Team::Blue, BLUE, &[p(0)])
        .await
        .unwrap();
    match again.next_push().await.unwrap() {
        Push::Observation(o) => {
            assert_eq!(
                o.tick,
                Tick::new(5),
                "rejoined at the tick the match waits on"
            );
            again.send_actions(o.tick, &stay(&[p(0)])).await.unwrap();
        }
        other => panic!("{other:?}"),
    }
    let k = tokio::spawn(async move { play_out(&mut keeper, &[p(1)]).await });
    let (end, errors) = play_out(&mut again, &joined.players).await;
    let (kend, _) = k.await.unwrap();
    assert!(errors.is_empty(), "{errors:?}");
    assert_eq!(end.reason, EndReason::Finished);
    assert_eq!(end.tick, Tick::new(40));
    assert_eq!(kend, end);
    // Ticks 0..5 answered by the first connection, 6..40 by the second:
    // the only possible miss is tick 5 if the rejoin raced its deadline,
    // which is a minute away.
    assert_eq!(end.misses.blue[0], 0, "{:?}", end.misses);
    server.stop().await;
}

/// Issue 15 A.5, the ordering behind the flaky test above made certain: a
/// robot's client answers tick 0 and disconnects while the tick still waits
/// on the keeper, and the robot is taken back before the keeper answers. Its
/// action for tick 0 stands, so the new connection is not sent tick 0 again
/// (a tick its robot has answered) but tick 1 once the keeper answers, and
/// the robot has no miss.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn rejoining_robot_is_not_sent_a_tick_it_already_answered() {
    let mut cfg = config(20);
    cfg.start_players = 2;
    cfg.deadline_ms = 600_000;
    let server = start(cfg).await;
    let mut keeper = join_robot(&server, "keeper", Team::Blue, BLUE, p(1)).await;
    let mut first = join_robot(&server, "robot-0", Team::Blue, BLUE, p(0)).await;
    for c in [&mut keeper, &mut first] {
        assert!(
            matches!(c.next_push().await.unwrap(), Push::Observation(o) if o.tick == Tick::ZERO)
        );
    }
    // The connection forwards the action to the match before it reads the
    // end of the stream, so the match has it before it hears of the leave.
    first
        .send_actions(Tick::ZERO, &stay(&[p(0)]))
        .await
        .unwrap();
    drop(first);
    let mut again = Client::connect(server.addr(), "robot-0 again")
        .await
        .unwrap();
    wait_until_blue_0_is_free(&mut again).await;
    let joined = again
        .join(Some(MatchId(1)), Team::Blue, BLUE, &[p(0)])
        .await
        .unwrap();
    assert_eq!(
        match_info(&mut again, MatchId(1)).await.tick,
        Tick::ZERO,
        "tick 0 still waits on the keeper"
    );
    keeper
        .send_actions(Tick::ZERO, &stay(&[p(1)]))
        .await
        .unwrap();
    match again.next_push().await.unwrap() {
        Push::Observation(o) => assert_eq!(o.tick, Tick::new(1), "its robot had answered tick 0"),
        other => panic!("{other:?}"),
    }
    again
        .send_actions(Tick::new(1), &stay(&[p(0)]))
        .await
        .unwrap();
    let k = tokio::spawn(async move { play_out(&mut keeper, &[p(1)]).await });
    let (end, errors) = play_out(&mut again, &joined.players).await;
    let (kend, kerrors) = k.await.unwrap();
    assert!(
        errors.is_empty() && kerrors.is_empty(),
        "{errors:?} {kerrors:?}"
    );
    assert_eq!(end.reason, EndReason::Finished);
    assert_eq!(end.tick, Tick::new(20));
    assert_eq!(kend, end);
    assert_eq!(end.misses.blue, [0, 0, 0, 0], "{:?}", end.misses);
    server.stop().await;
}

/// Issue 15 A.3, as docs/PROTOCOL.md says: a robot whose client left stands
/// without counting misses and without the match waiting for it, and a
/// finished match's `taken` is all false. The deadline is ten minutes, so a
/// match that waited for the robot, or a miss counted at a deadline, would
/// show.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn left_robots_count_no_misses_and_a_finished_match_has_no_takers() {
    let mut cfg = config(20);
    cfg.start_players = 2;
    cfg.deadline_ms = 600_000;
    let server = start(cfg).await;
    let mut leaver = join_robot(&server, "leaver", Team::Blue, BLUE, p(0)).await;
    let mut stayer = join_robot(&server, "stayer", Team::Red, RED, p(0)).await;
    let stayer = tokio::spawn(async move {
        let out = play_out(&mut stayer, &[p(0)]).await;
        (stayer, out)
    });
    // Answer ticks 0..3, then leave with tick 3 unanswered.
    loop {
        match leaver.next_push().await.unwrap() {
            Push::Observation(o) if o.tick < Tick::new(3) => {
                leaver.send_actions(o.tick, &stay(&[p(0)])).await.unwrap()
            }
            Push::Observation(_) => break,
            other => panic!("{other:?}"),
        }
    }
    assert_eq!(leaver.leave().await.unwrap(), MatchId(1));
    let (mut stayer, (end, errors)) = stayer.await.unwrap();
    assert!(errors.is_empty(), "{errors:?}");
    assert_eq!(end.tick, Tick::new(20));
    assert_eq!(end.misses.blue, [0; 4], "17 ticks stood, none a miss");
    assert_eq!(end.misses.red, [0; 4]);
    let info = match_info(&mut stayer, MatchId(1)).await;
    assert_eq!(info.state, MatchState::Finished);
    assert_eq!(info.taken.blue, [false; 4]);
    assert_eq!(
        info.taken.red, [false; 4],
        "its last client's slot is cleared"
    );
    server.stop().await;
}

/// What an observer saw of one match: ticks and how it ended.
#[derive(Debug, Clone, PartialEq)]
struct Seen {
    ticks: u64,
    end: Option<EndReason>,
}

struct Recorder {
    id: MatchId,
    seen: Arc<Mutex<Vec<(MatchId, Seen)>>>,
    ticks: u64,
}

impl MatchObserver for Recorder {
    fn on_start(&mut self, _info: &MatchInfo, _game: &Match) {}
    fn on_tick(&mut self, _record: &TickRecord<'_>) {
        self.ticks += 1;
    }
    fn on_end(&mut self, end: &MatchEnd, _game: &Match) {
        let seen = Seen {
            ticks: self.ticks,
            end: Some(end.reason),
        };
        self.seen.lock().unwrap().push((self.id, seen));
    }
}

async fn start_with(
    cfg: ServerConfig,
    hooks: Hooks,
) -> (
    SocketAddr,
    oneshot::Sender<()>,
    tokio::task::JoinHandle<Result<(), ServerError>>,
) {
    let listener = TcpListener::bind("127.0.0.1:0").await.unwrap();
    let addr = listener.local_addr().unwrap();
    let (tx, rx) = oneshot::channel::<()>();
    let task = tokio::spawn(naosoccer_server::run_with(
        listener,
        cfg,
        hooks,
        async move {
            let _ = rx.await;
        },
    ));
    (addr, tx, task)
}

/// A match whose task panics (injected) ends with an `internal` error and a
/// `match_end` (reason `internal`) to its clients and a finished observer
/// (the recorder's hook); the other match plays to its end and the server
/// keeps serving.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_panicking_match_ends_alone() {
    let seen = Arc::new(Mutex::new(Vec::new()));
    let factory_seen = seen.clone();
    let hooks = Hooks {
        observer: Some(Arc::new(move |info: &MatchInfo| {
            Some(Box::new(Recorder {
                id: info.match_id,
                seen: factory_seen.clone(),
                ticks: 0,
            }) as Box<dyn MatchObserver>)
        })),
        ..Hooks::default()
    };
    let mut cfg = config(60);
    cfg.matches = 0;
    // The first match created panics at tick 20.
    cfg.panic_at.insert(MatchId(1), 20);
    let dir = std::env::temp_dir().join(format!("naosoccer-panic-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    cfg.record_dir = Some(dir.clone());
    let (addr, stop, task) = start_with(cfg, hooks).await;
    let mut admin = Client::connect(addr, "admin").await.unwrap();
    let mk = || CreateMatch {
        token: ADMIN.into(),
        start_players: Some(4),
        ..Default::default()
    };
    let doomed = admin.create_match(mk()).await.unwrap().match_id;
    assert_eq!(doomed, MatchId(1));
    let healthy = admin.create_match(mk()).await.unwrap().match_id;

    let mut a = Client::connect(addr, "a").await.unwrap();
    let mut b = Client::connect(addr, "b").await.unwrap();
    a.join(Some(doomed), Team::Blue, BLUE, &all_players())
        .await
        .unwrap();
    b.join(Some(healthy), Team::Blue, BLUE, &all_players())
        .await
        .unwrap();
    let players = all_players();
    let ((a_end, a_errors), (b_end, b_errors)) =
        tokio::join!(play_out(&mut a, &players), play_out(&mut b, &players));
    assert_eq!(a_end.reason, EndReason::Internal);
    assert_eq!(a_end.tick, Tick::new(20), "ticks 0..20 played, 20 panicked");
    assert_eq!(a_errors.len(), 1, "{a_errors:?}");
    assert_eq!(a_errors[0].code, ErrorCode::Internal);
    assert_eq!(
        (a_errors[0].in_reply_to.as_deref(), a_errors[0].tick),
        (Some("action"), Some(Tick::new(20))),
        "the error is paired with the actions for the tick that failed"
    );
    assert_eq!(b_end.reason, EndReason::Finished);
    assert_eq!(b_end.tick, Tick::new(60));
    assert!(b_errors.is_empty(), "{b_errors:?}");

    // The server goes on: the doomed match is listed as finished, and the
    // connection that played it may join another.
    let info = match_info(&mut admin, doomed).await;
    assert_eq!(info.state, MatchState::Finished);
    assert_eq!(a.ping(3).await.unwrap(), 3);
    let again = admin.create_match(mk()).await.unwrap().match_id;
    a.join(Some(again), Team::Red, RED, &[p(2)]).await.unwrap();

    stop.send(()).unwrap();
    task.await.unwrap().unwrap();
    let mut seen = seen.lock().unwrap().clone();
    seen.sort_by_key(|(id, _)| *id);
    let expect = |ticks, end| Seen {
        ticks,
        end: Some(end),
    };
    assert_eq!(
        seen,
        vec![
            (doomed, expect(20, EndReason::Internal)),
            (healthy, expect(60, EndReason::Finished)),
            (again, expect(0, EndReason::Shutdown)),
        ]
    );
    // Both recordings are finished files: the panicked match's up to its
    // last played tick.
    for (id, ticks) in [(doomed, 20), (healthy, 60)] {
        let path = dir.join(format!("match-{}-seed-42.mcap", id.0));
        let path = if path.exists() {
            path
        } else {
            std::fs::read_dir(&dir)
                .unwrap()
                .map(|e| e.unwrap().path())
                .find(|p| {
                    p.file_name()
                        .and_then(|n| n.to_str())
                        .is_some_and(|n| n.starts_with(&format!("match-{}-", id.0)))
                })
                .expect("a recording per match")
        };
        let rec = naosoccer_record::Recording::read_file(&path).unwrap();
        assert!(rec.is_complete(), "{}: {:?}", path.display(), rec.truncated);
        assert_eq!(rec.actions.len(), ticks, "{}", path.display());
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Issue 15: the fault-injection hook is server configuration, not part of
/// the protocol. A `create_match` that still names `panic_at_tick` is an
/// ordinary request (unknown fields are ignored) and its match plays out.
#[tokio::test]
async fn issue_15_panic_at_tick_on_the_wire_injects_nothing() {
    let mut cfg = config(10);
    cfg.matches = 0;
    let server = start(cfg).await;
    let mut admin = Client::connect(server.addr(), "admin").await.unwrap();
    let req = serde_json::json!({
        "type": "create_match", "token": ADMIN, "start_players": 4, "panic_at_tick": 1
    });
    admin.send_raw(&frame::encode(&req).unwrap()).await.unwrap();
    let id = match admin.recv().await.unwrap() {
        ServerMsg::MatchCreated(c) => c.info.match_id,
        other => panic!("expected match_created, got {other:?}"),
    };
    let mut c = Client::connect(server.addr(), "c").await.unwrap();
    c.join(Some(id), Team::Blue, BLUE, &all_players())
        .await
        .unwrap();
    let (end, errors) = play_out(&mut c, &all_players()).await;
    assert_eq!(end.reason, EndReason::Finished);
    assert_eq!(end.tick, Tick::new(10));
    assert!(errors.is_empty(), "{errors:?}");
    server.stop().await;
}

/// Raw TCP: a peer that connects and sends nothing is refused by the
/// hello deadline from the config, not a constant.
#[tokio::test(start_paused = true)]
async fn hello_deadline_comes_from_the_config() {
    let mut cfg = config(10);
    cfg.limits.hello_timeout_ms = 2_500;
    let server = start(cfg).await;
    let stream = TcpStream::connect(server.addr).await.unwrap();
    let start = tokio::time::Instant::now();
    let err = first_error(stream).await;
    assert_eq!(err.code, ErrorCode::DeadlineExceeded);
    assert!(err.message.contains("hello_timeout_ms"), "{err}");
    assert_eq!(start.elapsed(), std::time::Duration::from_millis(2_500));
    server.stop().await;
}

/// Reads the first frame of a connection that never said hello.
async fn first_error(stream: TcpStream) -> ErrorMsg {
    use tokio::io::AsyncReadExt;
    let (mut r, _w) = stream.into_split();
    let mut len = [0u8; 4];
    r.read_exact(&mut len).await.unwrap();
    let mut body = vec![0u8; u32::from_be_bytes(len) as usize];
    r.read_exact(&mut body).await.unwrap();
    match serde_json::from_slice(&body).unwrap() {
        ServerMsg::Error(e) => {
            assert!(e.fatal);
            e
        }
        other => panic!("{other:?}"),
    }
}

/// Issue 39: `match_list` holds the 64 most recently finished matches at
/// every moment (it held 65 until the next `create_match`), chosen by when
/// they finished, not by id; a forgotten match is `not_found`.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn issue_39_the_list_keeps_the_64_most_recently_finished_matches() {
    let mut cfg = config(100);
    cfg.start_players = 8; // nobody joins: every match waits until ended
    let server = start(cfg).await;
    let mut admin = Client::connect(server.addr(), "admin").await.unwrap();
    let finished = |list: &[MatchInfo]| -> Vec<u64> {
        list.iter()
            .filter(|m| m.state == MatchState::Finished)
            .map(|m| m.match_id.0)
            .collect()
    };
    // Match 1 (from the config) waits while 64 others are made and ended.
    for n in 1..=64u64 {
        let info = admin
            .create_match(CreateMatch {
                token: ADMIN.into(),
                ..CreateMatch::default()
            })
            .await
            .unwrap();
        assert_eq!(info.match_id, MatchId(n + 1));
        admin.end_match(ADMIN, info.match_id).await.unwrap();
        let list = admin.list_matches().await.unwrap();
        assert_eq!(finished(&list), (2..=n + 1).collect::<Vec<_>>());
        assert_eq!(list[0].match_id, MatchId(1));
    }
    // Match 1 finishes last: it is kept, and match 2, the earliest to
    // finish, is forgotten at once.
    admin.end_match(ADMIN, MatchId(1)).await.unwrap();
    let list = admin.list_matches().await.unwrap();
    let mut expected = vec![1];
    expected.extend(3..=65);
    assert_eq!(finished(&list), expected);
    assert_eq!(list.len(), 64);
    let err = admin.end_match(ADMIN, MatchId(2)).await.unwrap_err();
    assert_eq!(err.code(), Some(ErrorCode::NotFound));
    let err = admin
        .join(
            Some(MatchId(2)),
            Team::Blue,
            BLUE,
            &[Player::new(0).unwrap()],
        )
        .await
        .unwrap_err();
    assert_eq!(err.code(), Some(ErrorCode::NotFound));
    server.stop().await;
}
