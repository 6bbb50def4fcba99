//! Issue 39: the kick-off rule and set plays enforced as docs/PROTOCOL.md
//! ("Restarts and set plays") says, on the real sim with staged situations.

use std::f32::consts::FRAC_PI_2;

use naosoccer_proto::{Action, Event, GoalPhase, RobotId, Score, SetPlayKind, Team, ROBOTS};
use naosoccer_referee::{FirstKickOff, Match, MatchConfig};

const STAY: [Action; ROBOTS] = [Action::Stay; ROBOTS];

fn robot(team: Team, player: usize) -> RobotId {
    RobotId::new(team, player).unwrap()
}

fn blue_kicks_off() -> MatchConfig {
    let mut cfg = MatchConfig::default();
    cfg.rules.first_kickoff = FirstKickOff::Blue;
    cfg
}

/// Every robot but `keep` to the touch lines, out of the way of staged play.
fn clear_the_pitch(m: &mut Match, keep: &[usize]) {
    for i in 0..ROBOTS {
        if keep.contains(&i) {
            continue;
        }
        let x = -2.4 + 0.6 * (i % 4) as f32 + if i < 4 { 0.0 } else { 0.3 };
        let y = if i < 4 { 2.0 } else { -2.0 };
        m.sim_mut().place_robot(i, x, y, 0.0);
    }
}

/// The first `set_play` event's kind, team and spot.
fn first_award(events: &[Event]) -> Option<(SetPlayKind, Team, f32, f32)> {
    events.iter().find_map(|e| match *e {
        Event::SetPlay {
            play, team, x, y, ..
        } => Some((play, team, x, y)),
        _ => None,
    })
}

fn ball_xy(m: &Match) -> (f32, f32) {
    let b = m.sim().snapshot().ball.pos;
    (b[0], b[1])
}

fn dist_to(m: &Match, i: usize, (x, y): (f32, f32)) -> f32 {
    let p = m.sim().snapshot().robots[i].pos;
    (p[0] - x).hypot(p[1] - y)
}

/// Blue's striker stands right behind the ball on the centre spot at its
/// kick-off, the other robots cleared away, and shoots straight at red's
/// goal until the ball is in or `limit` ticks pass. Returns every event.
fn direct_kick_off_shot(cfg: &MatchConfig) -> (Match, Vec<Event>) {
    let mut m = Match::new(cfg, 11).unwrap();
    let striker = robot(Team::Blue, 1).index();
    clear_the_pitch(&mut m, &[]);
    m.sim_mut().place_robot(striker, -0.17, 0.0, 0.0);
    assert_eq!(
        m.set_play().map(|s| (s.0, s.1)),
        Some((SetPlayKind::KickOff, Team::Blue)),
        "staged during blue's kick-off"
    );
    let mut act = STAY;
    act[striker] = Action::Shoot;
    let mut events = Vec::new();
    for _ in 0..60 {
        let ev = m.step(&act).to_vec();
        let done = ev
            .iter()
            .any(|e| matches!(e, Event::Goal { .. } | Event::GoalDisallowed { .. }));
        events.extend(ev);
        // One kick only: the striker stands once the ball is on its way.
        act[striker] = Action::Stay;
        if done {
            break;
        }
    }
    (m, events)
}

#[test]
fn a_goal_straight_from_the_kick_off_is_disallowed_and_restarts_with_a_goal_kick() {
    let (m, events) = direct_kick_off_shot(&blue_kicks_off());
    assert!(
        events.iter().any(|e| matches!(
            e,
            Event::GoalDisallowed {
                team: Team::Blue,
                reason: naosoccer_proto::DisallowReason::DirectKickOff,
                ..
            }
        )),
        "no disallowed goal in {events:?}"
    );
    assert!(!events.iter().any(|e| matches!(e, Event::Goal { .. })));
    assert_eq!(m.score(), Score::default());
    assert_eq!(m.stats().blue.goals, 0);
    assert_eq!(m.stats().blue.goals_disallowed, 1);
    // No goal reward for either team.
    assert!(m.rewards(Team::Blue).iter().all(|r| *r < 1.0));
    // A goal kick for red, the ball on the front corner of red's goal area.
    let (kind, team, _) = m.set_play().expect("a set play");
    assert_eq!((kind, team), (SetPlayKind::GoalKick, Team::Red));
    let set_play = first_award(&events).expect("a set_play event");
    assert_eq!(set_play.0, SetPlayKind::GoalKick);
    assert_eq!(set_play.1, Team::Red);
    assert!((set_play.2 - 2.4).abs() < 1e-5 && (set_play.3.abs() - 1.7).abs() < 1e-5);
    let (bx, by) = ball_xy(&m);
    assert!((bx - set_play.2).abs() < 1e-5 && (by - set_play.3).abs() < 1e-5);
    assert_eq!(m.stats().red.goal_kicks, 1);
}

#[test]
fn with_direct_kick_off_goals_on_the_same_shot_is_a_goal_from_a_restart() {
    let mut cfg = blue_kicks_off();
    cfg.rules.direct_kick_off_goals = true;
    let (m, events) = direct_kick_off_shot(&cfg);
    let goal = events
        .iter()
        .find_map(|e| match e {
            Event::Goal {
                team,
                scorer,
                phase,
                ..
            } => Some((*team, *scorer, *phase)),
            _ => None,
        })
        .expect("a goal");
    assert_eq!(
        goal,
        (
            Team::Blue,
            Some(robot(Team::Blue, 1)),
            Some(GoalPhase::Restart)
        )
    );
    let s = m.stats().blue;
    assert_eq!(
        (
            s.goals,
            s.goals_restart,
            s.goals_open_play,
            s.goals_own_goal
        ),
        (1, 1, 0, 0)
    );
}

#[test]
fn a_goal_after_a_staged_open_ball_is_open_play_and_an_own_goal_is_one() {
    let mut m = Match::new(&MatchConfig::default(), 4).unwrap();
    m.clear_set_play();
    clear_the_pitch(&mut m, &[]);
    // A red robot kicks the ball into its own goal (+x is red's).
    let r2 = robot(Team::Red, 2).index();
    m.sim_mut().place_robot(r2, 2.3, 0.0, 0.0);
    m.sim_mut().place_ball(2.47, 0.0);
    let mut act = STAY;
    act[r2] = Action::Shoot;
    let mut events = Vec::new();
    for _ in 0..60 {
        let ev = m.step(&act).to_vec();
        act[r2] = Action::Stay;
        let done = ev
            .iter()
            .any(|e| matches!(e, Event::Goal { .. } | Event::BallOut { .. }));
        events.extend(ev);
        if done {
            break;
        }
    }
    let goal = events.iter().find_map(|e| match e {
        Event::Goal {
            team,
            scorer,
            phase,
            ..
        } => Some((*team, *scorer, *phase)),
        _ => None,
    });
    assert_eq!(
        goal,
        Some((Team::Blue, None, Some(GoalPhase::OwnGoal))),
        "{events:?}"
    );
    assert_eq!(m.stats().blue.goals_own_goal, 1);
}

/// A ball just over the touch line at x = 1.0 (nobody touched it: red's
/// kick-in, red defends +x), a red robot standing on the spot, one blue
/// robot lying inside the circle, one standing inside it and one between
/// the circle and the edge of the ground.
fn staged_kick_in() -> (Match, Vec<Event>) {
    let mut m = Match::new(&MatchConfig::default(), 6).unwrap();
    m.clear_set_play();
    let (r1, b1, b2, b3) = (
        robot(Team::Red, 1).index(),
        robot(Team::Blue, 1).index(),
        robot(Team::Blue, 2).index(),
        robot(Team::Blue, 3).index(),
    );
    clear_the_pitch(&mut m, &[]);
    // Blue 3 falls first, then lies inside the circle round the spot.
    m.sim_mut().place_robot(b3, 0.6, 2.0, 0.0);
    m.sim_mut().push_robot(b3, [25.0, 0.0, 0.0]);
    for _ in 0..30 {
        m.step(&STAY);
        if m.is_down(robot(Team::Blue, 3)) {
            break;
        }
    }
    assert!(m.is_down(robot(Team::Blue, 3)), "blue 3 fell");
    let lying_at = dist_to(&m, b3, (1.0, 2.2));
    assert!(lying_at < 0.6, "blue 3 lies {lying_at} m from the spot");
    // Red 1 stands on the spot (the ball comes back in on it), blue 1
    // near the line, blue 2 just off the pitch beside the spot.
    m.sim_mut().place_robot(r1, 1.0, 2.2, FRAC_PI_2);
    m.sim_mut().place_robot(b1, 1.3, 2.0, FRAC_PI_2);
    m.sim_mut().place_robot(b2, 0.75, 2.45, 0.0);
    // (`place_ball` keeps a ball within the lines.)
    let moved = m.sim_mut().place_ball_exact(1.0, 2.5);
    assert_eq!(
        moved, [false; ROBOTS],
        "the ball is put down clear of everyone"
    );
    let mut events = Vec::new();
    for _ in 0..40 {
        let ev = m.step(&STAY).to_vec();
        let done = ev.iter().any(|e| matches!(e, Event::SetPlay { .. }));
        events.extend(ev);
        if done {
            break;
        }
    }
    (m, events)
}

#[test]
fn the_ball_goes_exactly_on_its_spot_and_ball_out_set_play_and_observation_agree() {
    let (m, events) = staged_kick_in();
    let out = events
        .iter()
        .find_map(|e| match e {
            Event::BallOut { x, y, .. } => Some((*x, *y)),
            _ => None,
        })
        .expect("ball_out");
    let award = first_award(&events).expect("set_play");
    assert_eq!((award.0, award.1), (SetPlayKind::KickIn, Team::Red));
    // The documented spot: where it left, 5 cm inside the touch line.
    assert!((out.1 - 2.2).abs() < 1e-5, "{out:?}");
    assert_eq!(out, (award.2, award.3));
    assert_eq!(ball_xy(&m), out);
    // The observation (red's frame is turned half round).
    let o = m.observe(Team::Red, 0);
    assert!((o.ball.x + out.0).abs() < 1e-5 && (o.ball.y + out.1).abs() < 1e-5);
    // Red 1, which stood on the spot, stepped aside.
    let r1 = robot(Team::Red, 1).index();
    assert!(dist_to(&m, r1, out) > 0.1, "red 1 still on the spot");
}

#[test]
fn the_other_team_is_moved_out_of_the_circle_at_the_award_lying_or_near_the_line() {
    let (m, _) = staged_kick_in();
    let spot = ball_xy(&m);
    let radius = MatchConfig::default().rules.set_play_distance;
    for p in 0..4 {
        let i = robot(Team::Blue, p).index();
        let d = dist_to(&m, i, spot);
        assert!(d >= radius, "blue {p} at {d} m from the ball");
        let pos = m.sim().snapshot().robots[i].pos;
        assert!(pos[1] <= 2.5 + 1e-4, "blue {p} beyond the ground: {pos:?}");
    }
    // The lying one was stood up outside.
    assert!(!m.is_down(robot(Team::Blue, 3)));
}

#[test]
fn the_other_team_cannot_creep_in_or_kick_during_a_set_play() {
    let (mut m, _) = staged_kick_in();
    let spot = ball_xy(&m);
    let radius = MatchConfig::default().rules.set_play_distance;
    let (b1, b2, b3) = (
        robot(Team::Blue, 1).index(),
        robot(Team::Blue, 2).index(),
        robot(Team::Blue, 3).index(),
    );
    // Blue 1 on the edge facing the ball, blue 2 right behind it pushing
    // it in, blue 3 trying to kick.
    let toward = |x: f32, y: f32| (spot.1 - y).atan2(spot.0 - x);
    m.sim_mut()
        .place_robot(b1, 1.0, 2.2 - 0.63, toward(1.0, 1.57));
    m.sim_mut()
        .place_robot(b2, 1.0, 2.2 - 0.95, toward(1.0, 1.25));
    m.sim_mut().place_robot(b3, 0.2, 2.2, 0.0);
    let mut act = STAY;
    act[b1] = Action::Forward;
    act[b2] = Action::Forward;
    act[b3] = Action::Shoot;
    let mut closest = f32::MAX;
    let mut ticks = 0;
    while m.set_play().is_some() && ticks < 200 {
        m.step(&act);
        ticks += 1;
        if m.set_play().is_none() {
            break;
        }
        for p in 0..4 {
            closest = closest.min(dist_to(&m, robot(Team::Blue, p).index(), spot));
        }
        let s = &m.sim().snapshot().robots[b3];
        assert_eq!(s.command, Action::Stay, "blue 3's kick was not refused");
        assert!(!s.kicking);
    }
    assert!(ticks > 100, "the set play lasted {ticks} ticks");
    assert!(
        closest >= radius,
        "a blue robot came to {closest} m of the ball"
    );
    assert_eq!(ball_xy(&m), spot, "nobody played the ball");
}
