//! The `approach` action walks a robot round behind the ball and into it
//! facing the opponent goal, on the real pitch; the `facing` support spot
//! lies where the teammate nearest the ball will face when it gets there.

use std::f32::consts::PI;

use naosoccer_policy::actions::{
    approach_action, banned_actions, support_spot, DecisionConfig, SupportSpot,
    APPROACH_ONLY_BANNED, ROLE_BANNED,
};
use naosoccer_policy::obs::KickReach;
use naosoccer_policy::{to_action, NetAction};
use naosoccer_proto::{Action, Team, ROBOTS};
use naosoccer_referee::{Match, MatchConfig};

/// A default match with every robot but blue 1 and blue 2 on the touch
/// lines, blue 1 at `me` (x, y, heading), blue 2 at `mate` and the ball at
/// `ball`.
fn staged(me: (f32, f32, f32), mate: (f32, f32, f32), ball: (f32, f32)) -> Match {
    let mut m = Match::new(&MatchConfig::default(), 5).unwrap();
    for i in 0..ROBOTS {
        let x = -2.4 + 0.6 * (i % 4) as f32 + if i < 4 { 0.0 } else { 0.3 };
        let y = if i < 4 { 2.8 } else { -2.8 };
        m.sim_mut().place_robot(i, x, y, 0.0);
    }
    m.sim_mut().place_robot(1, me.0, me.1, me.2);
    m.sim_mut().place_robot(2, mate.0, mate.1, mate.2);
    m.sim_mut().place_ball(ball.0, ball.1);
    m.step(&[Action::Stay; ROBOTS]);
    m
}

fn half(m: &Match) -> [f32; 2] {
    let f = m.field();
    [f.half_length, f.half_width]
}

/// How far (rad) the robot that received `obs` faces off the line from the
/// ball to the middle of the opponent goal, on a pitch of half size `h`.
fn goal_offset(obs: &naosoccer_proto::Observation, h: [f32; 2]) -> f32 {
    let to_goal = (-obs.ball.y).atan2(h[0] - obs.ball.x);
    naosoccer_referee::rules::wrap_angle(obs.me().heading - to_goal)
}

/// Blue 1 stands between the ball and the opponent goal, its back to that
/// goal. `approach` takes it round the ball (not through it: the ball does
/// not go back toward blue's own goal) until the ball is in kick reach with
/// the robot facing the opponent goal, and then walks on with the ball.
#[test]
fn approach_goes_round_behind_the_ball_and_takes_it_toward_the_goal() {
    let mut m = staged((0.6, 0.1, PI), (-2.0, -1.5, 0.0), (0.0, 0.0));
    let h = half(&m);
    let reach = KickReach::default();
    let mut reached = None;
    for t in 0..1500 {
        let obs = m.observe(Team::Blue, 1);
        assert!(
            obs.ball.x > -0.3,
            "tick {t}: the robot pushed the ball back to ({}, {})",
            obs.ball.x,
            obs.ball.y
        );
        if reach.in_reach(&obs) {
            let off = goal_offset(&obs, h);
            assert!(
                off.abs() < 0.6,
                "tick {t}: in reach facing {off} rad off the goal"
            );
            reached = Some((t, obs.ball.x));
            break;
        }
        let mut joint = [Action::Stay; ROBOTS];
        joint[1] = to_action(NetAction::Approach, &obs, h, SupportSpot::Ahead, &reach);
        assert_eq!(joint[1], approach_action(&obs, h));
        m.step(&joint);
    }
    let (t, x0) = reached.expect("the ball never came into kick reach");
    assert!(
        t > 50,
        "it went round the ball, which takes time (tick {t})"
    );
    for _ in 0..150 {
        let obs = m.observe(Team::Blue, 1);
        let mut joint = [Action::Stay; ROBOTS];
        joint[1] = approach_action(&obs, h);
        m.step(&joint);
    }
    let x1 = m.observe(Team::Blue, 1).ball.x;
    assert!(x1 > x0 + 0.3, "it walked on with the ball: {x0} -> {x1}");
}

/// From anywhere round the ball, facing any way, `approach` brings the ball
/// into kick reach with the robot facing the opponent goal (within 0.8 rad:
/// the line-up's 0.5 rad and the walk's cone): twelve starts
/// on a circle of 0.5 m round a ball in the centre circle, each facing a
/// different way. (A wide point on the edge of the region where the ball is
/// in the way once left a robot turning left and right on the spot.)
#[test]
fn approach_reaches_the_ball_from_every_side() {
    let reach = KickReach::default();
    for k in 0..12 {
        let a = k as f32 * PI / 6.0;
        let me = (0.2 + 0.5 * a.cos(), 0.1 + 0.5 * a.sin(), a * 2.3);
        let mut m = staged(me, (-2.0, -1.5, 0.0), (0.2, 0.1));
        let h = half(&m);
        let mut reached = None;
        for t in 0..900 {
            let obs = m.observe(Team::Blue, 1);
            if reach.in_reach(&obs) {
                let off = goal_offset(&obs, h);
                assert!(
                    off.abs() < 0.8,
                    "start {k}: in reach {off} rad off the goal"
                );
                reached = Some(t);
                break;
            }
            let mut joint = [Action::Stay; ROBOTS];
            joint[1] = approach_action(&obs, h);
            m.step(&joint);
        }
        assert!(
            reached.is_some(),
            "start {k} at {me:?}: no ball in reach in 90 s"
        );
    }
}

/// `approach` is a step of the protocol's walk and turns, and a lying robot
/// stays.
#[test]
fn approach_is_walking_and_turning() {
    let m = staged((-1.0, 0.0, 0.0), (-2.0, -1.5, 0.0), (-0.6, 0.0));
    let h = half(&m);
    let mut obs = m.observe(Team::Blue, 1);
    // In line behind the ball, facing it: walk into it.
    assert_eq!(approach_action(&obs, h), Action::Forward);
    // Facing away: turn back toward it.
    obs.own[1].heading = 2.0;
    assert_eq!(approach_action(&obs, h), Action::TurnRight);
    obs.own[1].heading = -2.0;
    assert_eq!(approach_action(&obs, h), Action::TurnLeft);
    obs.own[1].fallen = true;
    assert_eq!(approach_action(&obs, h), Action::Stay);
}

/// The `facing` spot: 1.5 m beyond the ball on the line from the teammate
/// nearest the ball, 1 m to the robot's side of it. With the kicker coming
/// from the opponent half the spot is behind the ball (toward blue's own
/// goal); from its own half, ahead, where the `ahead` spot also is.
#[test]
fn the_facing_spot_lies_where_the_kicker_faces() {
    // Blue 1 comes from +x toward the ball at (0, 0); blue 2 at (0.5, -1).
    let m = staged((0.4, 0.0, PI), (0.5, -1.0, 0.0), (0.0, 0.0));
    let h = half(&m);
    let obs = m.observe(Team::Blue, 2);
    let ball = (obs.ball.x, obs.ball.y);
    let facing = support_spot(&obs, h, SupportSpot::Facing);
    let kx = obs.own[1].x;
    let dir = (ball.0 - kx).signum();
    assert!(dir < 0.0);
    assert!(
        (facing[0] - (ball.0 - 1.5)).abs() < 0.05,
        "{facing:?} (ball {ball:?})"
    );
    assert!((facing[1] - (ball.1 - 1.0)).abs() < 0.05, "{facing:?}");
    let ahead = support_spot(&obs, h, SupportSpot::Ahead);
    assert!((ahead[0] - (ball.0 + 1.5)).abs() < 1e-5, "{ahead:?}");
    assert!((ahead[1] - (ball.1 - 1.0)).abs() < 1e-5, "{ahead:?}");
    // The support action walks toward the spot it is given.
    assert_ne!(
        to_action(
            NetAction::Support,
            &obs,
            h,
            SupportSpot::Facing,
            &KickReach::default()
        ),
        to_action(
            NetAction::Support,
            &obs,
            h,
            SupportSpot::Ahead,
            &KickReach::default()
        )
    );
    // The kicker on blue's own side of the ball: both spots ahead.
    let m = staged((-0.4, 0.0, 0.0), (0.5, -1.0, 0.0), (0.0, 0.0));
    let obs = m.observe(Team::Blue, 2);
    let facing = support_spot(&obs, h, SupportSpot::Facing);
    let ahead = support_spot(&obs, h, SupportSpot::Ahead);
    assert!((facing[0] - ahead[0]).abs() < 0.05, "{facing:?} {ahead:?}");
    assert!((facing[1] - ahead[1]).abs() < 0.05, "{facing:?} {ahead:?}");
}

/// Under roles a robot that does not chase may not `approach`; with
/// `approach_only` nobody walks `forward` or turns.
#[test]
fn approach_masks() {
    let m = staged((-1.0, 0.0, 0.0), (1.5, 1.5, 0.0), (-0.82, 0.0));
    let chaser = m.observe(Team::Blue, 1);
    let other = m.observe(Team::Blue, 2);
    let mut d = DecisionConfig {
        pass: true,
        support: true,
        chasers: 1,
        approach: true,
        ..DecisionConfig::team()
    };
    assert_eq!(d.actions(), NetAction::Approach.index() + 1);
    let pass_bit = |o| {
        if naosoccer_proto::pass_receiver(o).is_some() {
            0
        } else {
            NetAction::Pass.bit()
        }
    };
    assert_eq!(banned_actions(&chaser, true, &d), pass_bit(&chaser));
    assert_eq!(
        banned_actions(&other, false, &d),
        ROLE_BANNED | NetAction::Approach.bit() | NetAction::Pass.bit()
    );
    d.approach_only = true;
    assert_eq!(
        banned_actions(&chaser, true, &d),
        APPROACH_ONLY_BANNED | pass_bit(&chaser)
    );
    d.chasers = 0;
    assert_eq!(
        banned_actions(&other, false, &d),
        APPROACH_ONLY_BANNED | NetAction::Pass.bit()
    );
}
