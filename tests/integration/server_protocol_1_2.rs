//! Protocol 1.2's additions over a real server on an ephemeral loopback
//! port (issue 15 B): the referee's events pushed with every observation,
//! the pitch announced in `joined`, `end_match`.

use crate::common;

use common::server::*;
use naosoccer_client::{Client, ClientError, Push};
use naosoccer_policy::PolicyKind;
use naosoccer_proto::msg::{
    CreateMatch, EndReason, ErrorCode, Frame, Hello, MatchEnd, MatchId, MatchState, Pitch, Player,
    PlayerAction, Version, PROTOCOL_NAME,
};
use naosoccer_proto::{Action, Event, RobotId, Team, Tick};

fn all_players() -> Vec<Player> {
    Player::all().collect()
}

/// `joined` carries the pitch of the server's match configuration, so a
/// client needs no copy of it; a configuration other than the default shows
/// it is read from the match, not hard-wired.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn joined_announces_the_pitch() {
    let mut cfg = config(20);
    cfg.start_players = 8; // nothing is played: only the reply matters
    cfg.match_cfg.sim.field_length = 7.5;
    cfg.match_cfg.sim.field_width = 5.0;
    cfg.match_cfg.sim.goal_width = 1.5;
    cfg.match_cfg.rules.b_d = 0.25;
    cfg.match_cfg.rules.b_rad = 0.5;
    cfg.match_cfg.control_hz = 5.0;
    let sim = cfg.match_cfg.sim.clone();
    let server = start(cfg).await;
    let mut c = Client::connect(server.addr(), "pitch").await.unwrap();
    let joined = c
        .join(Some(MatchId(1)), Team::Red, RED, &all_players())
        .await
        .unwrap();
    assert_eq!(joined.control_hz, 5.0);
    assert_eq!(
        joined.pitch,
        Some(Pitch {
            field_length: 7.5,
            field_width: 5.0,
            goal_width: 1.5,
            goal_depth: sim.goal_depth,
            goal_height: sim.goal_height,
            ball_radius: sim.ball_radius,
            b_d: 0.25,
            b_rad: 0.5,
            frame: Frame::Team,
        })
    );
    drop(c);
    server.stop().await;
}

/// Every observation carries the events of the tick that led to it, each
/// with the tick it happened on, and `match_end` the last tick's: together
/// they are the in-process match's events for the same seed and policies.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn events_arrive_with_their_tick_and_equal_the_in_process_match() {
    let mut cfg = config(600);
    cfg.deadline_ms = 30_000; // no misses, however loaded the machine
    cfg.start_players = 4; // blue joins; red is the server's scripted fill
    let match_cfg = cfg.match_cfg.clone();
    let server = start(cfg).await;
    let mut c = Client::connect(server.addr(), "events").await.unwrap();
    let players = all_players();
    c.join(Some(MatchId(1)), Team::Blue, BLUE, &players)
        .await
        .unwrap();
    let mut policies: Vec<_> = players
        .iter()
        .map(|p| PolicyKind::Scripted.build(42, RobotId::new(Team::Blue, p.index()).unwrap()))
        .collect();
    let mut received: Vec<Event> = Vec::new();
    let mut first = true;
    let end = loop {
        match c.next_push().await.unwrap() {
            Push::Observation(o) => {
                if first {
                    assert!(o.events.is_empty(), "no tick led to the first observation");
                    first = false;
                }
                for e in &o.events {
                    assert_eq!(
                        e.tick().map(|t| t + 1),
                        Some(o.tick),
                        "{e:?} in the observation of tick {}",
                        o.tick
                    );
                }
                received.extend(o.events);
                let actions: Vec<PlayerAction> = players
                    .iter()
                    .zip(&o.observations)
                    .zip(&mut policies)
                    .map(|((p, obs), policy)| PlayerAction {
                        player: *p,
                        action: policy.act(obs),
                    })
                    .collect();
                c.send_actions(o.tick, &actions).await.unwrap();
            }
            Push::MatchEnd(e) => break e,
            Push::Error(e) => panic!("{e}"),
        }
    };
    assert_eq!(end.reason, EndReason::Finished);
    assert_eq!(end.misses.blue, [0; 4]);
    assert!(!end.events.is_empty(), "the last tick ends the match");
    for e in &end.events {
        assert_eq!(
            e.tick().map(|t| t + 1),
            Some(end.tick),
            "{e:?} in match_end"
        );
    }
    assert_eq!(end.events.last(), Some(&Event::End { tick: end.tick - 1 }));
    received.extend(end.events.iter().cloned());

    let mut expected: Vec<Event> = Vec::new();
    let out = naosoccer_eval::run::play_match(
        &match_cfg,
        42,
        &PolicyKind::Scripted,
        &PolicyKind::Scripted,
        |t| expected.extend_from_slice(t.events),
    )
    .unwrap();
    assert_eq!(end.tick, Tick::new(out.ticks));
    assert_eq!(
        end.state_hash,
        format!("{:016x}", out.state_hash),
        "the same match"
    );
    assert_eq!(received, expected);
    // Not a trivial match: kicks, a restart and the end at least.
    for kind in ["kick", "kick_off", "end"] {
        assert!(
            received
                .iter()
                .any(|e| serde_json::to_value(e).unwrap()["kind"] == kind),
            "no {kind} event in {received:?}"
        );
    }
    server.stop().await;
}

async fn next_observation_tick(c: &mut Client) -> u64 {
    match c.next_push().await.unwrap() {
        Push::Observation(o) => o.tick.get(),
        other => panic!("expected an observation, got {other:?}"),
    }
}

async fn next_match_end(c: &mut Client) -> MatchEnd {
    match c.next_push().await.unwrap() {
        Push::MatchEnd(e) => e,
        other => panic!("expected match_end, got {other:?}"),
    }
}

fn stay(players: &[Player]) -> Vec<PlayerAction> {
    players
        .iter()
        .map(|p| PlayerAction {
            player: *p,
            action: Action::Stay,
        })
        .collect()
}

fn code(r: Result<naosoccer_proto::msg::MatchInfo, ClientError>) -> Option<ErrorCode> {
    r.unwrap_err().code()
}

/// `end_match` (admin) ends a running match at the tick it is waiting on:
/// every client of it gets its `match_end` (reason `ended`; `shutdown` for a
/// client that said 1.1), then the admin the final description. A waiting
/// match can be ended too; a finished one cannot.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn end_match_ends_a_match_with_match_end_to_every_client() {
    let mut cfg = config(600);
    cfg.deadline_ms = 600_000; // the match waits for blue at tick 5
    cfg.start_players = 5;
    let server = start(cfg).await;
    let mut admin = Client::connect(server.addr(), "admin").await.unwrap();
    let mut blue = Client::connect(server.addr(), "blue").await.unwrap();
    let old = Hello {
        protocol: PROTOCOL_NAME.into(),
        version: Version { major: 1, minor: 1 },
        client: Some("a 1.1 robot".into()),
    };
    let stream = tokio::net::TcpStream::connect(server.addr()).await.unwrap();
    let mut red = Client::handshake(stream, &old).await.unwrap();
    let team = all_players();
    let one = [Player::new(1).unwrap()];
    blue.join(Some(MatchId(1)), Team::Blue, BLUE, &team)
        .await
        .unwrap();
    red.join(Some(MatchId(1)), Team::Red, RED, &one)
        .await
        .unwrap();
    for t in 0..=5 {
        assert_eq!(next_observation_tick(&mut blue).await, t);
        assert_eq!(next_observation_tick(&mut red).await, t);
        if t < 5 {
            blue.send_actions(Tick::new(t), &stay(&team)).await.unwrap();
        }
        red.send_actions(Tick::new(t), &stay(&one)).await.unwrap();
    }

    // Wrong token, unknown match: refused, the match goes on.
    assert_eq!(
        code(admin.end_match(BLUE, MatchId(1)).await),
        Some(ErrorCode::PermissionDenied)
    );
    assert_eq!(
        code(admin.end_match(ADMIN, MatchId(9)).await),
        Some(ErrorCode::NotFound)
    );
    let info = admin.end_match(ADMIN, MatchId(1)).await.unwrap();
    assert_eq!(info.state, MatchState::Finished);
    assert_eq!(info.tick, Tick::new(5), "ended at the tick it waited on");

    let b = next_match_end(&mut blue).await;
    let r = next_match_end(&mut red).await;
    assert_eq!(b.reason, EndReason::Ended);
    assert_eq!(r.reason, EndReason::Shutdown, "1.1 knows no `ended`");
    for e in [&b, &r] {
        assert_eq!(e.match_id, MatchId(1));
        assert_eq!(e.tick, Tick::new(5));
        assert_eq!(e.score, info.score);
        assert!(e.events.is_empty(), "observation 5 carried tick 4's events");
    }
    assert_eq!(b.state_hash, r.state_hash);
    assert_eq!(
        code(admin.end_match(ADMIN, MatchId(1)).await),
        Some(ErrorCode::FailedPrecondition)
    );
    // Back in the lobby: the ended match cannot be joined.
    let err = blue
        .join(Some(MatchId(1)), Team::Blue, BLUE, &team)
        .await
        .unwrap_err();
    assert_eq!(err.code(), Some(ErrorCode::FailedPrecondition));

    // A match still waiting for its players ends at tick 0, and an admin
    // that plays in the match gets its own match_end too.
    let created = admin
        .create_match(CreateMatch {
            token: ADMIN.into(),
            start_players: Some(8),
            ..CreateMatch::default()
        })
        .await
        .unwrap();
    admin
        .join(Some(created.match_id), Team::Blue, BLUE, &one)
        .await
        .unwrap();
    let info = admin.end_match(ADMIN, created.match_id).await.unwrap();
    assert_eq!((info.state, info.tick), (MatchState::Finished, Tick::ZERO));
    let end = next_match_end(&mut admin).await;
    assert_eq!((end.reason, end.tick), (EndReason::Ended, Tick::ZERO));
    server.stop().await;
}

/// A client that joins a running match gets, with its first observation,
/// the events of the tick that led to it: the same as every other client.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_client_joining_mid_match_gets_the_events_of_the_tick_before() {
    let mut cfg = config(600);
    cfg.deadline_ms = 600_000; // the match waits for blue at tick 1
    cfg.start_players = 4;
    let server = start(cfg).await;
    let mut blue = Client::connect(server.addr(), "blue").await.unwrap();
    let team = all_players();
    blue.join(Some(MatchId(1)), Team::Blue, BLUE, &team)
        .await
        .unwrap();
    assert_eq!(next_observation_tick(&mut blue).await, 0);
    blue.send_actions(Tick::ZERO, &stay(&team)).await.unwrap();
    let seen_by_blue = match blue.next_push().await.unwrap() {
        Push::Observation(o) => o,
        other => panic!("{other:?}"),
    };
    assert_eq!(seen_by_blue.tick, Tick::new(1));
    assert!(
        seen_by_blue.events.iter().any(|e| matches!(
            e,
            Event::KickOff {
                tick: Tick::ZERO,
                ..
            }
        )),
        "the start's kick-off comes with tick 0's events: {:?}",
        seen_by_blue.events
    );
    let mut red = Client::connect(server.addr(), "red").await.unwrap();
    red.join(Some(MatchId(1)), Team::Red, RED, &[Player::new(2).unwrap()])
        .await
        .unwrap();
    let first = match red.next_push().await.unwrap() {
        Push::Observation(o) => o,
        other => panic!("{other:?}"),
    };
    assert_eq!(first.tick, Tick::new(1));
    assert_eq!(first.events, seen_by_blue.events);
    drop((blue, red));
    server.stop().await;
}

/// A match created with a level of the scripted ladder as its fill plays
/// that level in the empty slots: the same match as `match --blue
/// scripted:1 --red scripted:5` in process. It is described with values
/// every client knows: `fill` "scripted" and `fill_team` "scripted:5".
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_level_of_the_ladder_fills_the_empty_slots() {
    use naosoccer_policy::ScriptedParams;
    use naosoccer_proto::msg::Fill;
    let cfg = config(300);
    let match_cfg = cfg.match_cfg.clone();
    let server = start(cfg).await;
    let mut c = Client::connect(server.addr(), "ladder").await.unwrap();
    let info = c
        .create_match(CreateMatch {
            token: ADMIN.into(),
            seed: Some(9),
            fill: Some("scripted:5".parse::<Fill>().unwrap()),
            start_players: Some(4),
            ..CreateMatch::default()
        })
        .await
        .unwrap();
    assert_eq!(info.fill, Fill::Scripted);
    assert_eq!(info.fill_team.as_deref(), Some("scripted:5"));
    let players = all_players();
    c.join(Some(info.match_id), Team::Blue, BLUE, &players)
        .await
        .unwrap();
    let one = PolicyKind::scripted_with(ScriptedParams::level(1).unwrap());
    let mut policies: Vec<_> = players
        .iter()
        .map(|p| one.build(9, RobotId::new(Team::Blue, p.index()).unwrap()))
        .collect();
    let end = loop {
        match c.next_push().await.unwrap() {
            Push::Observation(o) => {
                let actions: Vec<PlayerAction> = players
                    .iter()
                    .zip(&o.observations)
                    .zip(&mut policies)
                    .map(|((p, obs), policy)| PlayerAction {
                        player: *p,
                        action: policy.act(obs),
                    })
                    .collect();
                c.send_actions(o.tick, &actions).await.unwrap();
            }
            Push::MatchEnd(e) => break e,
            Push::Error(e) => panic!("{e}"),
        }
    };
    let five: PolicyKind = "scripted:5".parse().unwrap();
    let out = naosoccer_eval::run::play_match(&match_cfg, 9, &one, &five, |_| {}).unwrap();
    assert_eq!(end.state_hash, format!("{:016x}", out.state_hash));
    // A fill the protocol does not know is refused as an invalid argument.
    assert!("scripted:6".parse::<Fill>().is_err());
    server.stop().await;
}
