//! The `defend` action walks a robot back onto the line from the ball to
//! its own goal and turns it to face the ball there, on the real pitch and
//! for either team; any robot may choose it, and it holds like `support`.

use std::f32::consts::PI;

use naosoccer_policy::actions::{
    banned_actions, defend_action, defend_spot, DecisionConfig, Hold, SupportSpot, DEFEND_BEHIND,
    DEFEND_GOAL_MIN, ROLE_BANNED, SUPPORT_ARRIVE,
};
use naosoccer_policy::obs::KickReach;
use naosoccer_policy::{to_action, NetAction};
use naosoccer_proto::{Action, Observation, Team, ROBOTS};
use naosoccer_referee::{Match, MatchConfig};

/// A default match with every robot on the touch lines but `robot`, at
/// `at` (x, y, heading, field frame), and the ball at `ball`.
fn staged(robot: usize, at: (f32, f32, f32), ball: (f32, f32)) -> Match {
    let mut m = Match::new(&MatchConfig::default(), 5).unwrap();
    for i in 0..ROBOTS {
        let x = -2.4 + 0.6 * (i % 4) as f32 + if i < 4 { 0.0 } else { 0.3 };
        let y = if i < 4 { 2.8 } else { -2.8 };
        m.sim_mut().place_robot(i, x, y, 0.0);
    }
    m.sim_mut().place_robot(robot, at.0, at.1, at.2);
    m.sim_mut().place_ball(ball.0, ball.1);
    m.step(&[Action::Stay; ROBOTS]);
    m
}

fn half(m: &Match) -> [f32; 2] {
    let f = m.field();
    [f.half_length, f.half_width]
}

/// How far (m) the robot that received `obs` stands from the segment
/// between the ball and the centre of its own goal, and whether it stands
/// between them (its projection on the segment inside it).
fn off_the_line(obs: &Observation, h: [f32; 2]) -> (f32, bool) {
    let me = obs.me();
    let (gx, gy) = (-h[0], 0.0);
    let (dx, dy) = (obs.ball.x - gx, obs.ball.y - gy);
    let len2 = dx * dx + dy * dy;
    let t = ((me.x - gx) * dx + (me.y - gy) * dy) / len2;
    let (px, py) = (gx + t * dx, gy + t * dy);
    ((me.x - px).hypot(me.y - py), (0.0..1.0).contains(&t))
}

/// A robot of `team` standing upfield, its back to its own goal, the ball
/// in its own half: `defend` brings it back between the ball and its goal,
/// about DEFEND_BEHIND from the ball, facing the ball.
fn walks_back_between_ball_and_goal(team: Team) {
    // Field frame: blue defends x < 0, red x > 0; red's observation is the
    // mirror image, so the same staging mirrored tests the same thing.
    let s = if team == Team::Blue { 1.0 } else { -1.0 };
    let robot = if team == Team::Blue { 1 } else { 5 };
    let heading = if team == Team::Blue { 0.0 } else { PI };
    let mut m = staged(robot, (s * 1.5, 1.0, heading), (s * -1.2, -0.6));
    let h = half(&m);
    let player = robot % 4;
    let start = m.observe(team, player);
    assert!(
        !off_the_line(&start, h).1,
        "staged upfield, not between ball and goal"
    );
    let mut arrived = None;
    for t in 0..1200 {
        let obs = m.observe(team, player);
        let step = to_action(
            NetAction::Defend,
            &obs,
            h,
            SupportSpot::Facing,
            &KickReach::default(),
        );
        assert_eq!(step, defend_action(&obs, h));
        let spot = defend_spot(&obs, h);
        let me = obs.me();
        if (spot[0] - me.x).hypot(spot[1] - me.y) <= SUPPORT_ARRIVE && step == Action::Stay {
            arrived = Some((t, obs));
            break;
        }
        let mut joint = [Action::Stay; ROBOTS];
        joint[robot] = step;
        m.step(&joint);
    }
    let (t, obs) = arrived.expect("never arrived at the defending spot facing the ball");
    let (off, between) = off_the_line(&obs, h);
    assert!(
        between && off < SUPPORT_ARRIVE,
        "{team:?} tick {t}: {off} m off the line"
    );
    let me = obs.me();
    let d = (obs.ball.x - me.x).hypot(obs.ball.y - me.y);
    assert!(
        (d - DEFEND_BEHIND).abs() < SUPPORT_ARRIVE,
        "{team:?}: {d} m from the ball"
    );
    let to_ball = (obs.ball.y - me.y).atan2(obs.ball.x - me.x);
    let facing = naosoccer_referee::rules::wrap_angle(me.heading - to_ball).abs();
    assert!(facing < 0.5, "{team:?}: faces {facing} rad off the ball");
}

#[test]
fn defend_walks_a_blue_robot_back_between_ball_and_goal() {
    walks_back_between_ball_and_goal(Team::Blue);
}

#[test]
fn defend_walks_a_red_robot_back_between_ball_and_goal() {
    walks_back_between_ball_and_goal(Team::Red);
}

/// With the ball at the goal mouth, the spot stays DEFEND_GOAL_MIN out
/// from the goal's centre, in front of it, not inside it.
#[test]
fn the_defending_spot_stays_in_front_of_the_goal() {
    let m = staged(1, (0.0, 0.0, 0.0), (-2.9, 0.1));
    let h = half(&m);
    let obs = m.observe(Team::Blue, 1);
    let spot = defend_spot(&obs, h);
    assert!(spot[0] > -h[0], "{spot:?}");
    assert!(
        ((spot[0] + h[0]).hypot(spot[1]) - DEFEND_GOAL_MIN).abs() < 0.05,
        "{spot:?}"
    );
    // Far from goal: DEFEND_BEHIND short of the ball, on its line to goal.
    let m = staged(1, (0.0, 0.0, 0.0), (1.0, 1.0));
    let obs = m.observe(Team::Blue, 1);
    let spot = defend_spot(&obs, h);
    let d = (obs.ball.x - spot[0]).hypot(obs.ball.y - spot[1]);
    assert!((d - DEFEND_BEHIND).abs() < 1e-4, "{spot:?}");
    let cross = (obs.ball.x + h[0]) * spot[1] - obs.ball.y * (spot[0] + h[0]);
    assert!(cross.abs() < 1e-4, "{spot:?} is off the line");
}

/// `defend` makes a ninth output; robots that do not chase may choose it;
/// without `approach` the eighth output is always masked.
#[test]
fn defend_masks_and_action_count() {
    let m = staged(1, (-1.0, 0.0, 0.0), (-0.82, 0.0));
    let chaser = m.observe(Team::Blue, 1);
    let other = m.observe(Team::Blue, 2);
    let d = DecisionConfig {
        pass: true,
        support: true,
        chasers: 1,
        defend: true,
        ..DecisionConfig::team()
    };
    assert_eq!(d.actions(), NetAction::Defend.index() + 1);
    assert_eq!(d.actions(), 9);
    for obs in [&chaser, &other] {
        let bans = banned_actions(obs, false, &d);
        assert_eq!(bans & NetAction::Defend.bit(), 0);
        assert_ne!(bans & NetAction::Approach.bit(), 0);
    }
    assert_eq!(banned_actions(&other, false, &d) & ROLE_BANNED, ROLE_BANNED);
    let with_approach = DecisionConfig {
        approach: true,
        ..d
    };
    assert_eq!(with_approach.actions(), 9);
    assert_eq!(
        banned_actions(&chaser, false, &with_approach) & NetAction::Approach.bit(),
        0
    );
    // A configuration without the field (an older team) has no `defend`.
    let old: DecisionConfig =
        serde_json::from_str(r#"{"persist": 3, "pass": true, "support": true}"#).unwrap();
    assert!(!old.defend);
    assert_eq!(old.actions(), 7);
    let json = serde_json::to_string(&d).unwrap();
    assert!(json.contains("\"defend\":true"), "{json}");
}

/// Under `support_hold`, a `defend` holds until the robot reaches its spot
/// (after `persist` ticks at least), as a held `support` does.
#[test]
fn a_held_defend_ends_on_arrival() {
    let d = DecisionConfig {
        pass: true,
        support: true,
        support_hold: 60,
        defend: true,
        ..DecisionConfig::team()
    };
    // The spot is (-2, 0), 0.5 m away, the robot facing it; the ball
    // stays more than 0.6 m away, so only arriving ends the hold early.
    let mut m = staged(1, (-1.7, 0.4, -2.21), (-1.0, 0.0));
    let h = half(&m);
    let mut hold = Hold::default();
    let mut obs = m.observe(Team::Blue, 1);
    assert!(hold.must_decide(&obs));
    hold.start(NetAction::Defend, obs.tick, &d, h);
    let mut ended = None;
    for t in 1..60 {
        let mut joint = [Action::Stay; ROBOTS];
        joint[1] = to_action(
            hold.held(&obs),
            &obs,
            h,
            d.support_spot,
            &KickReach::default(),
        );
        m.step(&joint);
        obs = m.observe(Team::Blue, 1);
        if hold.must_decide(&obs) {
            ended = Some((t, obs));
            break;
        }
    }
    let (t, obs) = ended.expect("a held defend that never ends before support_hold");
    assert!(t >= d.persist as usize, "ended after {t} ticks");
    let spot = defend_spot(&obs, h);
    let me = obs.me();
    assert!(
        (spot[0] - me.x).hypot(spot[1] - me.y) <= SUPPORT_ARRIVE,
        "ended {} m from its spot",
        (spot[0] - me.x).hypot(spot[1] - me.y)
    );
}

/// A robot straight upfield of the ball, facing its own goal: `defend`
/// goes round the ball rather than through it, so the ball is not pushed
/// toward the goal, and the robot still reaches its spot.
#[test]
fn defend_goes_round_a_ball_in_its_way() {
    let mut m = staged(1, (0.6, 0.05, PI), (-0.5, 0.0));
    let h = half(&m);
    let ball0 = m.observe(Team::Blue, 1).ball;
    let mut arrived = false;
    for t in 0..1500 {
        let obs = m.observe(Team::Blue, 1);
        let moved = (obs.ball.x - ball0.x).hypot(obs.ball.y - ball0.y);
        assert!(moved < 0.05, "tick {t}: the ball was pushed {moved} m");
        let spot = defend_spot(&obs, h);
        let me = obs.me();
        let step = defend_action(&obs, h);
        if (spot[0] - me.x).hypot(spot[1] - me.y) <= SUPPORT_ARRIVE && step == Action::Stay {
            arrived = true;
            break;
        }
        let mut joint = [Action::Stay; ROBOTS];
        joint[1] = step;
        m.step(&joint);
    }
    assert!(arrived, "never reached the defending spot");
}
