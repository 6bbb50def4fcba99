//! Protocol 1.5 against a real server on an ephemeral port: `create_match`
//! from a scenario (played to its end condition, refused when bad), and the
//! admin's `set_state` (the next observation shows it, its event arrives,
//! every bad request refused, a recording of it replays exactly).

use crate::common;

use common::server::*;
use naosoccer_client::{Client, ClientError, Push};
use naosoccer_proto::msg::{
    CreateMatch, EndReason, ErrorCode, Fill, Hello, MatchEnd, MatchId, ObservationMsg, Player,
    SetState, Version, PROTOCOL_NAME,
};
use naosoccer_proto::{Action, BallPlacement, Event, RobotPlacement, Team, Tick, ROBOTS};
use naosoccer_record::{replay, Recording, ReplayOutcome};
use naosoccer_referee::{Match, MatchConfig, Scenario};

/// The ball rolls into the goal the own team attacks; one own robot stands
/// aside; it is 1 - 2 with 10 s of the first half played.
const ROLL_IN: &str = r#"
name = "roll-in"
duration = 5.0

[ball]
x = 2.5
y = 0.2
vx = 2.0

[[robot]]
side = "own"
player = 1
x = 0.0
y = 1.0

[state]
score = { own = 1, opponent = 2 }
elapsed = 10.0

[[end]]
when = "goal_for"
outcome = "success"

[[end]]
when = "ball_out"
outcome = "failure"
"#;

fn players() -> Vec<Player> {
    Player::all().collect()
}

async fn next_observation(c: &mut Client) -> ObservationMsg {
    match c.next_push().await.unwrap() {
        Push::Observation(o) => o,
        other => panic!("expected an observation, got {other:?}"),
    }
}

/// Plays `stay` for the joined players to the match's end.
async fn stay_to_the_end(c: &mut Client, players: &[Player]) -> MatchEnd {
    play_out(c, players).await.0
}

/// The scenario played in process with every robot standing, to its end
/// condition: the final tick, the state hash and how it ended.
fn in_process(cfg: &MatchConfig, seed: u64, own: Team) -> (Tick, String, &'static str, u64) {
    let s = Scenario::from_toml(ROLL_IN, None).unwrap();
    let mut m = Match::with_scenario(cfg, seed, &s, own).unwrap();
    let judge = s.judge(cfg, own, m.tick());
    loop {
        let events = m.step(&[Action::Stay; ROBOTS]).to_vec();
        if let Some(e) = judge.check(&m, &events) {
            return (
                m.tick(),
                format!("{:016x}", m.state_hash()),
                e.kind.name(),
                e.ticks,
            );
        }
    }
}

fn server_error(r: Result<impl std::fmt::Debug, ClientError>) -> (ErrorCode, String) {
    match r.unwrap_err() {
        ClientError::Server(e) => (e.code, e.message),
        other => panic!("expected a server error, got {other:?}"),
    }
}

/// A match created from a scenario starts at its tick and score, is
/// described as started from it, plays to its end condition and reports
/// how it ended in `match_end`, the same match as in process; for either
/// colour of the own team.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn create_match_with_a_scenario_plays_to_its_end_condition() {
    let cfg = config(600);
    let match_cfg = cfg.match_cfg.clone();
    let server = start(cfg).await;
    let mut admin = Client::connect(server.addr(), "admin").await.unwrap();
    for (own, seed) in [(Team::Blue, 5), (Team::Red, 6)] {
        let info = admin
            .create_match(CreateMatch {
                token: ADMIN.into(),
                seed: Some(seed),
                fill: Some(Fill::Idle),
                start_players: Some(1),
                scenario: Some(ROLL_IN.into()),
                scenario_team: (own == Team::Red).then_some(Team::Red),
                ..CreateMatch::default()
            })
            .await
            .unwrap();
        let s = info.scenario.as_ref().expect("described as a scenario");
        assert_eq!((s.name.as_str(), s.team), ("roll-in", own));
        assert_eq!(info.tick, Tick::new(100), "10 s into the first half");
        assert_eq!(*info.score.get(own), 1);
        assert_eq!(*info.score.get(own.other()), 2);
        let listed = admin.list_matches().await.unwrap();
        let l = listed.iter().find(|m| m.match_id == info.match_id).unwrap();
        assert_eq!(l.scenario, info.scenario);

        // The scenario's own robot, played by a client.
        let me = [Player::new(1).unwrap()];
        let mut c = Client::connect(server.addr(), "own robot").await.unwrap();
        let token = if own == Team::Blue { BLUE } else { RED };
        c.join(Some(info.match_id), own, token, &me).await.unwrap();
        let end = stay_to_the_end(&mut c, &me).await;
        let (tick, hash, ending, ticks) = in_process(&match_cfg, seed, own);
        assert_eq!(end.reason, EndReason::Finished);
        assert_eq!(end.tick, tick);
        assert_eq!(end.state_hash, hash, "the same match as in process");
        assert_eq!(*end.score.get(own), 2, "the own team scored");
        let s = end.scenario.expect("match_end says how the play ended");
        assert_eq!((s.name.as_str(), s.team), ("roll-in", own));
        assert_eq!(
            (s.ending.as_deref(), s.success, s.ticks),
            (Some(ending), Some(true), ticks)
        );
        assert_eq!(ending, "goal_for");
        assert!(
            end.events
                .iter()
                .any(|e| matches!(e, Event::Goal { team, .. } if *team == own)),
            "the last tick's goal comes with match_end: {:?}",
            end.events
        );
    }
    server.stop().await;
}

/// A bad scenario is refused with `invalid_argument` naming the field, and
/// nothing is created: the next match gets the next id.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_bad_scenario_is_refused_naming_the_field() {
    let server = start(config(600)).await;
    let mut admin = Client::connect(server.addr(), "admin").await.unwrap();
    let req = |scenario: Option<&str>, team: Option<Team>| CreateMatch {
        token: ADMIN.into(),
        scenario: scenario.map(str::to_owned),
        scenario_team: team,
        ..CreateMatch::default()
    };
    let cases = [
        (
            req(
                Some("[[robot]]\nside = \"own\"\nplayer = 4\nx = 0\ny = 0\n"),
                None,
            ),
            "`robot[0].player`",
        ),
        (req(Some("[ball]\nx = 3.5\ny = 0\n"), None), "`ball.x`"),
        (req(Some("speed = 1\n"), None), "speed"),
        (req(None, Some(Team::Red)), "scenario_team"),
    ];
    for (bad, field) in cases {
        let (code, message) = server_error(admin.create_match(bad).await);
        assert_eq!(code, ErrorCode::InvalidArgument, "{message}");
        assert!(message.contains(field), "{message} does not name {field}");
    }
    let good = admin.create_match(req(Some(ROLL_IN), None)).await.unwrap();
    assert_eq!(good.match_id, MatchId(2), "no id was used up");
    let listed = admin.list_matches().await.unwrap();
    assert_eq!(listed.len(), 2, "the configured match and the good one");
    server.stop().await;
}

/// `set_state` moves the ball and robots of a running match before its
/// next tick: the reply names that tick, the next observation shows the
/// new state, its `state_set` event comes with it; every bad request is
/// refused with its code, naming the field.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn set_state_moves_the_ball_and_a_robot() {
    let (server, mut admin, mut blue, id) = blue_waits_in_an_idle_match().await;
    let team = players();
    for t in 0..3 {
        assert_eq!(next_observation(&mut blue).await.tick, Tick::new(t));
        blue.send_actions(Tick::new(t), &stay(&team)).await.unwrap();
    }
    // Tick 3 is observed and waits for blue's actions.
    assert_eq!(next_observation(&mut blue).await.tick, Tick::new(3));
    let req = SetState {
        token: ADMIN.into(),
        match_id: id,
        ball: Some(BallPlacement {
            x: 1.0,
            y: 0.5,
            vx: 0.0,
            vy: 0.0,
        }),
        robots: vec![
            RobotPlacement {
                robot: 6, // red player 2
                x: -0.5,
                y: -1.7,
                heading: Some(0.0),
                fallen: false,
            },
            RobotPlacement {
                robot: 1, // blue player 1
                x: 0.5,
                y: 1.5,
                heading: None,
                fallen: true,
            },
        ],
    };

    // The bad ones first: nothing changes.
    let bad = |f: &dyn Fn(&mut SetState)| {
        let mut r = req.clone();
        f(&mut r);
        r
    };
    let cases: Vec<(SetState, ErrorCode, &str)> = vec![
        (
            bad(&|r| r.token = BLUE.into()),
            ErrorCode::PermissionDenied,
            "admin token",
        ),
        (
            bad(&|r| r.match_id = MatchId(9)),
            ErrorCode::NotFound,
            "no match 9",
        ),
        (
            bad(&|r| r.robots[1].robot = 8),
            ErrorCode::InvalidArgument,
            "`robots[1].robot` is 8",
        ),
        (
            bad(&|r| r.robots[0].robot = 1),
            ErrorCode::InvalidArgument,
            "`robots[1].robot` is 1",
        ),
        (
            bad(&|r| r.ball.as_mut().unwrap().x = -3.2),
            ErrorCode::InvalidArgument,
            "`ball.x` is -3.2",
        ),
        (
            bad(&|r| r.robots[0].y = 2.6),
            ErrorCode::InvalidArgument,
            "`robots[0].y` is 2.6",
        ),
        (
            bad(&|r| {
                r.ball = None;
                r.robots.clear()
            }),
            ErrorCode::InvalidArgument,
            "`ball`",
        ),
    ];
    for (r, want, text) in cases {
        let (code, message) = server_error(admin.set_state(r).await);
        assert_eq!(code, want, "{message}");
        assert!(message.contains(text), "{message} (wanted {text})");
    }

    let set = admin.set_state(req.clone()).await.unwrap();
    assert_eq!((set.match_id, set.tick), (id, Tick::new(3)));
    blue.send_actions(Tick::new(3), &stay(&team)).await.unwrap();
    let o = next_observation(&mut blue).await;
    assert_eq!(o.tick, Tick::new(4));
    assert_eq!(
        o.events.first(),
        Some(&Event::StateSet { tick: Tick::new(3) }),
        "{:?}",
        o.events
    );
    // Blue's frame is the world's. One tick of physics has passed.
    let seen = &o.observations[0];
    let near = |a: f32, b: f32| (a - b).abs() < 0.02;
    assert!(
        near(seen.ball.x, 1.0) && near(seen.ball.y, 0.5),
        "{:?}",
        seen.ball
    );
    let red2 = &seen.opponents[2];
    assert!(near(red2.x, -0.5) && near(red2.y, -1.7), "{red2:?}");
    assert!(near(red2.heading, 0.0), "{red2:?}");
    let blue1 = &seen.own[1];
    assert!(
        blue1.fallen && near(blue1.x, 0.5) && near(blue1.y, 1.5),
        "{blue1:?}"
    );
    assert_eq!(seen.set_play, None, "the kick-off ended");

    // Ended: a finished match refuses it.
    admin.end_match(ADMIN, id).await.unwrap();
    let (code, message) = server_error(admin.set_state(req).await);
    assert_eq!(code, ErrorCode::FailedPrecondition, "{message}");
    drop(blue);
    server.stop().await;
}

/// A change made while the match waits for its players is there in the
/// first observation, exactly; a client that said 1.4 gets the `state_set`
/// event too (an event of a kind it does not know, which it skips).
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn set_state_before_the_start_is_the_first_observation() {
    let (server, mut admin, match_id) = idle_match_waiting_for(1).await;
    let set = admin
        .set_state(SetState {
            token: ADMIN.into(),
            match_id,
            ball: Some(BallPlacement {
                x: -2.0,
                y: 1.25,
                vx: 0.0,
                vy: 0.0,
            }),
            robots: vec![RobotPlacement {
                robot: 2,
                x: 0.8,
                y: 1.9,
                heading: Some(1.0),
                fallen: false,
            }],
        })
        .await
        .unwrap();
    assert_eq!(set.tick, Tick::ZERO);
    let old = Hello {
        protocol: PROTOCOL_NAME.into(),
        version: Version { major: 1, minor: 4 },
        client: Some("a 1.4 robot".into()),
    };
    let stream = tokio::net::TcpStream::connect(server.addr()).await.unwrap();
    let mut c = Client::handshake(stream, &old).await.unwrap();
    let me = [Player::new(2).unwrap()];
    c.join(Some(match_id), Team::Blue, BLUE, &me).await.unwrap();
    let o = next_observation(&mut c).await;
    assert_eq!(o.tick, Tick::ZERO);
    let seen = &o.observations[0];
    assert_eq!((seen.ball.x, seen.ball.y), (-2.0, 1.25));
    assert_eq!((seen.own[2].x, seen.own[2].y), (0.8, 1.9));
    assert_eq!(seen.set_play, None);
    c.send_actions(Tick::ZERO, &stay(&me)).await.unwrap();
    let o = next_observation(&mut c).await;
    let kinds: Vec<_> = o
        .events
        .iter()
        .map(|e| serde_json::to_value(e).unwrap()["kind"].clone())
        .collect();
    assert_eq!(kinds, ["kick_off", "state_set"], "{:?}", o.events);
    drop(c);
    server.stop().await;
}

/// A server recording of a scenario match whose state an admin set (before
/// the start and twice during play) stores the scenario and the changes,
/// and replays to the same state hash; without the changes it does not.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_recorded_match_with_set_state_replays_exactly() {
    let dir = std::env::temp_dir().join(format!("naosoccer-set-state-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let mut cfg = config(600);
    cfg.deadline_ms = 600_000;
    cfg.record_dir = Some(dir.clone());
    cfg.matches = 0;
    let server = start(cfg).await;
    let mut admin = Client::connect(server.addr(), "admin").await.unwrap();
    // A scenario that lasts: no end condition but its 4 s.
    let scenario = "name = \"still\"\nduration = 4.0\n[ball]\nx = 0.5\ny = 0.0\n\
                    [[robot]]\nside = \"own\"\nplayer = 0\nx = -2.5\ny = 0\n\
                    [[robot]]\nside = \"opponent\"\nplayer = 3\nx = 1.0\ny = 0.5\n";
    let info = admin
        .create_match(CreateMatch {
            token: ADMIN.into(),
            seed: Some(11),
            fill: Some(Fill::Scripted),
            start_players: Some(1),
            scenario: Some(scenario.into()),
            scenario_team: Some(Team::Red),
            ..CreateMatch::default()
        })
        .await
        .unwrap();
    let id = info.match_id;
    let change = |x: f32, robot: u64| SetState {
        token: ADMIN.into(),
        match_id: id,
        ball: Some(BallPlacement {
            x,
            y: -0.4,
            vx: -1.5,
            vy: 0.5,
        }),
        robots: vec![RobotPlacement {
            robot,
            x: x + 0.3,
            y: -0.4,
            heading: None,
            fallen: false,
        }],
    };
    // Red's player 0 and blue's player 3 are the scenario's robots.
    let first = admin.set_state(change(1.0, 4)).await.unwrap();
    assert_eq!(first.tick, info.tick, "before the start");
    let me = [Player::new(0).unwrap()];
    let mut red = Client::connect(server.addr(), "red").await.unwrap();
    red.join(Some(id), Team::Red, RED, &me).await.unwrap();
    let mut sets = vec![info.tick];
    let end = loop {
        match red.next_push().await.unwrap() {
            Push::Observation(o) => {
                let t = o.tick.get() - info.tick.get();
                if t == 7 || t == 19 {
                    let s = admin
                        .set_state(change(-0.5 + t as f32 * 0.05, 3))
                        .await
                        .unwrap();
                    assert_eq!(s.tick, o.tick);
                    sets.push(o.tick);
                }
                red.send_actions(o.tick, &stay(&me)).await.unwrap();
            }
            Push::MatchEnd(e) => break e,
            Push::Error(e) => panic!("{e:?}"),
        }
    };
    assert_eq!(end.reason, EndReason::Finished);
    assert_eq!(
        end.scenario.as_ref().unwrap().ending.as_deref(),
        Some("time_up")
    );
    server.stop().await;

    let path = dir.join(format!("match-{}-seed-11.mcap", id.0));
    let rec = Recording::read_file(&path).unwrap();
    assert!(rec.is_complete(), "{:?}", rec.truncated);
    let s = rec
        .meta
        .scenario
        .as_ref()
        .expect("the scenario is recorded");
    assert_eq!((s.name.as_str(), s.own), ("still", Team::Red));
    let at: Vec<Tick> = rec.set_states.iter().map(|s| s.tick).collect();
    assert_eq!(at, sets);
    assert_eq!(rec.counts.get("/match/set_state"), Some(&3));
    assert_eq!(rec.stats.as_ref().unwrap().state_hash, end.state_hash);
    match replay(&rec).unwrap() {
        ReplayOutcome::Identical { ticks, truncated } => {
            assert_eq!(ticks, end.tick - info.tick);
            assert!(!truncated);
        }
        other => panic!("the recording does not replay: {other:?}"),
    }
    let mut without = rec.clone();
    without.set_states.clear();
    assert!(
        matches!(replay(&without).unwrap(), ReplayOutcome::Diverged { .. }),
        "the changes matter"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}
