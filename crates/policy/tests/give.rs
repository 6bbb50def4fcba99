//! The `give` action lines a robot up on a free teammate and passes to it,
//! on the real pitch; who it gives to, and when it may be chosen.

use std::f32::consts::PI;

use naosoccer_policy::actions::{
    banned_actions, give_action, give_target, DecisionConfig, SupportSpot, GIVE_MAX, GIVE_MIN,
};
use naosoccer_policy::obs::KickReach;
use naosoccer_policy::{to_action, NetAction};
use naosoccer_proto::{Action, Event, RobotId, Team, ROBOTS};
use naosoccer_referee::{Match, MatchConfig};

/// A default match (a 6 m by 4 m pitch) with blue 1 at `me` (x, y,
/// heading), blue 2 at `mate`, the ball at `ball`, blue 0 and blue 3 in
/// blue's corners and the red robots at the ends of the pitch, away from
/// the lanes the tests use.
fn staged(me: (f32, f32, f32), mate: (f32, f32, f32), ball: (f32, f32)) -> Match {
    let mut m = Match::new(&MatchConfig::default(), 5).unwrap();
    let others = [
        (0, -2.9, 1.9),
        (3, -2.9, -1.9),
        (4, 2.9, 1.9),
        (5, 2.9, -1.9),
        (6, -2.9, 0.9),
        (7, -2.9, -0.9),
    ];
    for (i, x, y) in others {
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

fn give() -> DecisionConfig {
    DecisionConfig {
        pass: true,
        support: true,
        approach: true,
        defend: true,
        give: true,
        ..DecisionConfig::team()
    }
}

/// Blue 2 1.5 m to the left of the ball: from eight starts round the
/// ball, facing every way, `give` walks blue 1 round the ball until it
/// faces blue 2, and kicks a `pass` with blue 2 as its receiver that
/// reaches blue 2 (the ball comes within 0.35 m of it).
#[test]
fn give_lines_up_and_passes_to_the_free_teammate() {
    let reach = KickReach::default();
    let blue = |p| RobotId::new(Team::Blue, p).unwrap();
    for k in 0..8 {
        let a = k as f32 * PI / 4.0;
        let me = (1.0 + 0.5 * a.cos(), 0.5 * a.sin(), a * 1.7);
        let mut m = staged(me, (1.3, 1.5, -PI / 2.0), (1.0, 0.0));
        let h = half(&m);
        let mut kicked = None;
        'ticks: for t in 0..1200 {
            let obs = m.observe(Team::Blue, 1);
            let mut joint = [Action::Stay; ROBOTS];
            if !obs.me().busy {
                joint[1] = to_action(NetAction::Give, &obs, h, SupportSpot::Facing, &reach);
                assert_eq!(joint[1], give_action(&obs, h, &reach));
                if joint[1] == Action::Pass {
                    assert!(
                        reach.in_reach(&obs),
                        "start {k}, tick {t}: a pass out of reach"
                    );
                }
            }
            for e in m.step(&joint) {
                if let Event::Kick {
                    robot, receiver, ..
                } = e
                {
                    kicked = Some((t, *robot, *receiver));
                    break 'ticks;
                }
            }
        }
        let (t, robot, receiver) = kicked.unwrap_or_else(|| panic!("start {k}: no kick in 120 s"));
        assert_eq!(robot, blue(1), "start {k}");
        assert_eq!(receiver, Some(blue(2)), "start {k}: tick {t}");
        let mut nearest = f32::INFINITY;
        for _ in 0..40 {
            m.step(&[Action::Stay; ROBOTS]);
            let o = m.observe(Team::Blue, 2);
            let d = (o.ball.x - o.own[2].x).hypot(o.ball.y - o.own[2].y);
            nearest = nearest.min(d);
        }
        assert!(
            nearest < 0.35,
            "start {k}: the pass missed blue 2 by {nearest} m"
        );
    }
}

/// Who `give` lines up on: a standing teammate 1.2-3.5 m from the ball
/// with a free lane, those ahead of the ball before those behind it; and
/// `give` is banned without one, and for a robot that does not chase.
#[test]
fn give_targets_free_teammates_in_range_ahead_first() {
    let m = staged((-0.5, 0.0, 0.0), (1.5, 1.0, 0.0), (0.0, 0.0));
    let mut base = m.observe(Team::Blue, 1);
    // Blue 0 and blue 3 lie on the touch line: only blue 2 counts.
    base.own[0].fallen = true;
    base.own[3].fallen = true;
    let d = give();
    assert_eq!(d.actions(), 10);
    let reach = KickReach::default();
    let may_give = |o: &naosoccer_proto::Observation, d: &DecisionConfig| {
        banned_actions(o, reach.in_reach(o), d) & NetAction::Give.bit() == 0
    };
    assert_eq!(give_target(&base), Some(2));
    assert!(may_give(&base, &d));

    // Too near, too far: no one.
    for (x, y) in [(0.5, 0.5), (0.0, GIVE_MAX + 0.2), (GIVE_MIN - 0.1, 0.0)] {
        let mut o = base.clone();
        o.own[2].x = x;
        o.own[2].y = y;
        assert_eq!(give_target(&o), None, "teammate at ({x}, {y})");
        assert!(!may_give(&o, &d));
    }
    // A lying teammate is no one to give to.
    let mut o = base.clone();
    o.own[2].fallen = true;
    assert_eq!(give_target(&o), None);
    // An opponent in the lane blocks it.
    let mut o = base.clone();
    o.opponents[0].x = 0.75;
    o.opponents[0].y = 0.5;
    assert_eq!(give_target(&o), None);
    // A teammate behind the ball is a target only when none is ahead.
    let mut o = base.clone();
    o.own[3].x = -2.0;
    o.own[3].y = 0.2;
    o.own[3].fallen = false;
    assert_eq!(give_target(&o), Some(2));
    o.own[2].fallen = true;
    assert_eq!(give_target(&o), Some(3));
    // Of two ahead, the one the robot walks least round the ball for: blue
    // 1 comes from -x, so blue 3 straight on beats blue 2 off to the side.
    let mut o = base.clone();
    o.own[3].x = 2.0;
    o.own[3].y = 0.0;
    o.own[3].fallen = false;
    assert_eq!(give_target(&o), Some(3));

    // Under roles only the chasers may give.
    let roles = DecisionConfig { chasers: 1, ..d };
    let other = m.observe(Team::Blue, 2);
    assert!(may_give(&base, &roles), "blue 1 is nearest the ball");
    assert!(!may_give(&other, &roles));
    // A team without `give` never bans it (it has no such output).
    let without = DecisionConfig { give: false, ..d };
    assert_eq!(without.actions(), 9);
    assert_eq!(
        banned_actions(&o, false, &without) & NetAction::Give.bit(),
        0
    );
}

/// `give` is a walk, a turn or the protocol's `pass`: with the ball in
/// reach and a receiver in the pass rule's cone, `pass`; a lying robot
/// stays.
#[test]
fn give_is_a_pass_when_the_rule_names_a_receiver() {
    let m = staged((-1.0, 0.0, 0.0), (1.5, 1.0, 0.0), (0.0, 0.0));
    let h = half(&m);
    let reach = KickReach::default();
    // Blue 1 with the ball just ahead, facing blue 2 2 m away.
    let mut obs = m.observe(Team::Blue, 1);
    obs.ball.x = 1.0;
    obs.ball.y = 0.0;
    obs.own[1].x = 0.8;
    obs.own[1].y = 0.0;
    obs.own[1].heading = 0.0;
    obs.own[2].x = 2.8;
    obs.own[2].y = 0.3;
    assert!(reach.in_reach(&obs));
    assert_eq!(naosoccer_proto::pass_receiver(&obs), Some(2));
    assert_eq!(give_target(&obs), Some(2));
    assert_eq!(give_action(&obs, h, &reach), Action::Pass);
    // Blue 2 off to the side, out of the cone: no pass, a line-up step.
    obs.own[2].x = 1.2;
    obs.own[2].y = 1.8;
    assert_eq!(give_target(&obs), Some(2));
    assert_ne!(give_action(&obs, h, &reach), Action::Pass);
    // Facing away from blue 2 (the ball out of reach behind it): a turn.
    obs.own[2].x = 2.8;
    obs.own[2].y = 0.3;
    obs.own[1].heading = PI;
    let step = give_action(&obs, h, &reach);
    assert!(
        matches!(step, Action::TurnLeft | Action::TurnRight),
        "{step:?}"
    );
    obs.own[1].fallen = true;
    assert_eq!(give_action(&obs, h, &reach), Action::Stay);
}

/// Under `support_hold`, one choice of `give` holds until the pass is made:
/// it ends once the ball is more than a metre away or there is no one to
/// give to, or after `support_hold` ticks; with no hold it lasts `persist`
/// ticks like any walk.
#[test]
fn a_held_give_lasts_until_the_ball_is_away() {
    use naosoccer_policy::actions::{Hold, GIVE_RELEASE_BALL};
    use naosoccer_proto::Tick;
    let m = staged((-0.5, 0.0, 0.0), (1.5, 1.0, 0.0), (0.0, 0.0));
    let h = half(&m);
    let mut obs = m.observe(Team::Blue, 1);
    obs.set_play = None;
    let at = |o: &naosoccer_proto::Observation, t: u64| {
        let mut o = o.clone();
        o.tick = Tick::new(t);
        o
    };
    let held = DecisionConfig {
        support_hold: 60,
        ..give()
    };
    let mut hold = Hold::default();
    assert!(hold.must_decide(&at(&obs, 10)));
    hold.start(NetAction::Give, Tick::new(10), &held, h);
    for t in 11..70 {
        assert!(!hold.must_decide(&at(&obs, t)), "tick {t}: still lining up");
        assert_eq!(hold.held(&at(&obs, t)), NetAction::Give);
    }
    assert!(hold.must_decide(&at(&obs, 70)), "support_hold ran out");
    // The ball away (the pass made): decide again.
    hold.start(NetAction::Give, Tick::new(70), &held, h);
    let mut away = at(&obs, 75);
    away.ball.x = obs.own[1].x + GIVE_RELEASE_BALL + 0.1;
    assert!(hold.must_decide(&away));
    // No one to give to: decide again.
    hold.start(NetAction::Give, Tick::new(80), &held, h);
    let mut alone = at(&obs, 85);
    alone.own[2].fallen = true;
    alone.own[3].fallen = true;
    alone.own[0].fallen = true;
    assert!(hold.must_decide(&alone));
    // Without a hold, three ticks (`persist`).
    let mut hold = Hold::default();
    hold.start(NetAction::Give, Tick::new(10), &give(), h);
    assert!(!hold.must_decide(&at(&obs, 12)));
    assert!(hold.must_decide(&at(&obs, 13)));
}
