//! Protocol 1.6 against a real server on an ephemeral port: a `pass` swung
//! toward a receiver is told apart from a shot. The admin sets a kicker
//! with the ball at its feet and a teammate in its cone; the kick event
//! names that teammate as `receiver`, the pass that follows is `aimed`, and
//! `match_end` counts it among `aimed_passes`. The same set-up with `shoot`
//! names no receiver: the teammate takes the ball, a pass that is not aimed.

use crate::common;

use common::server::*;
use naosoccer_client::Push;
use naosoccer_proto::msg::{MatchEnd, PlayerAction, SetState};
use naosoccer_proto::{Action, BallPlacement, Event, RobotId, RobotPlacement, Team, Tick};

/// Blue player 1 at (-1, 0) facing +x with the ball 0.18 m ahead; blue
/// player 2 1.5 m further on, facing the ball, so the pass rolls into it
/// whatever the kick's seeded noise; every other robot far from the line.
fn pass_set_up(match_id: naosoccer_proto::msg::MatchId) -> SetState {
    let at = |robot: u64, x: f32, y: f32, heading: f32| RobotPlacement {
        robot,
        x,
        y,
        heading: Some(heading),
        fallen: false,
    };
    SetState {
        token: ADMIN.into(),
        match_id,
        ball: Some(BallPlacement {
            x: -0.82,
            y: 0.0,
            vx: 0.0,
            vy: 0.0,
        }),
        robots: vec![
            at(0, -2.5, -1.5, 0.0),
            at(1, -1.0, 0.0, 0.0),
            at(2, 0.68, 0.0, std::f32::consts::PI),
            at(3, -2.0, -1.5, 0.0),
            at(4, 2.5, -1.8, 0.0),
            at(5, 2.0, -1.8, 0.0),
            at(6, 1.5, -1.8, 0.0),
            at(7, 1.0, -1.8, 0.0),
        ],
    }
}

/// Sets the kicker up at tick 3, has blue player 1 play `kick` until its
/// kick is reported and `stay` for 80 ticks more, then ends the match:
/// the kick and pass events blue received, and the `match_end`.
async fn kick_over_the_socket(kick: Action) -> (Vec<Event>, MatchEnd) {
    let (server, mut admin, mut blue, id) = blue_waits_in_an_idle_match().await;
    let team: Vec<_> = (0..4).map(p).collect();
    let mut events = Vec::new();
    let mut kicked_at: Option<Tick> = None;
    loop {
        let o = match blue.next_push().await.unwrap() {
            Push::Observation(o) => o,
            other => panic!("expected an observation, got {other:?}"),
        };
        for e in &o.events {
            if matches!(e, Event::Kick { .. } | Event::Pass { .. }) {
                kicked_at.get_or_insert(o.tick);
                events.push(e.clone());
            }
        }
        if o.tick == Tick::new(3) {
            admin.set_state(pass_set_up(id)).await.unwrap();
        }
        let done = kicked_at.is_some_and(|t| o.tick.get() >= t.get() + 80);
        if done {
            break;
        }
        let mut actions = stay(&team);
        if o.tick.get() >= 4 && kicked_at.is_none() {
            actions[1] = PlayerAction {
                player: p(1),
                action: kick,
            };
        }
        blue.send_actions(o.tick, &actions).await.unwrap();
        assert!(o.tick.get() < 200, "no kick by tick 200: {events:?}");
    }
    admin.end_match(ADMIN, id).await.unwrap();
    let end = loop {
        match blue.next_push().await.unwrap() {
            Push::MatchEnd(end) => break end,
            Push::Observation(_) | Push::Error(_) => {}
        }
    };
    drop(blue);
    server.stop().await;
    (events, end)
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_pass_names_its_receiver_and_counts_as_aimed() {
    let (kicker, mate) = (
        RobotId::new(Team::Blue, 1).unwrap(),
        RobotId::new(Team::Blue, 2).unwrap(),
    );
    let (events, end) = kick_over_the_socket(Action::Pass).await;
    assert!(
        matches!(events.first(), Some(Event::Kick { robot, receiver: Some(to), .. })
            if *robot == kicker && *to == mate),
        "{events:?}"
    );
    assert!(
        events
            .iter()
            .any(|e| matches!(e, Event::Pass { from, to, aimed: true, .. }
            if *from == kicker && *to == mate)),
        "{events:?}"
    );
    let blue = &end.stats.blue;
    assert_eq!((blue.passes, blue.aimed_passes), (1, 1), "{blue:?}");
    assert_eq!(end.stats.red.aimed_passes, 0);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_shot_a_teammate_takes_is_a_pass_but_not_aimed() {
    let (events, end) = kick_over_the_socket(Action::Shoot).await;
    assert!(
        matches!(events.first(), Some(Event::Kick { receiver: None, .. })),
        "{events:?}"
    );
    // The teammate straight ahead takes the shot: a pass, not an aimed one.
    assert!(
        events
            .iter()
            .any(|e| matches!(e, Event::Pass { aimed: false, .. })),
        "{events:?}"
    );
    let blue = &end.stats.blue;
    assert_eq!((blue.passes, blue.aimed_passes), (1, 0), "{blue:?}");
}
