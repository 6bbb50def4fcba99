use naosoccer_proto::{Action, Event, RobotId, SetPlayKind, Team, Tick, ROBOTS};

use super::*;
use crate::Match;

const EMPTY_GOAL: &str = r#"
name = "test"
duration = 10.0

[ball]
x = 2.0
y = 0.3
vx = 1.0

[[robot]]
side = "own"
player = 1
x = -0.25
y = 0.0
from = "ball"
heading = "ball"

[[robot]]
side = "opponent"
player = 0
x = 2.7
y = [-0.5, 0.5]
heading = 3.14159

[[end]]
when = "goal_for"
outcome = "success"

[[end]]
when = "region"
x = [-3.0, 0.0]
y = [-2.25, 2.25]
outcome = "failure"
"#;

fn err(text: &str) -> String {
    Scenario::from_toml(text, None).unwrap_err().to_string()
}

fn cfg() -> MatchConfig {
    MatchConfig::default()
}

#[test]
fn a_file_parses_with_its_defaults() {
    let s = Scenario::from_toml(EMPTY_GOAL, None).unwrap();
    assert_eq!(s.name, "test");
    assert_eq!(s.opponent, DEFAULT_OPPONENT);
    assert_eq!(s.duration, Some(10.0));
    assert_eq!(s.robots.len(), 2);
    assert_eq!(s.ends.len(), 2);
    assert_eq!(s.ends[0], (EndKind::GoalFor, true));
    s.check(&cfg()).unwrap();
    let named = Scenario::from_toml("", Some("stem")).unwrap();
    assert_eq!(named.name, "stem");
}

#[test]
fn bad_files_name_the_field() {
    let cases: &[(&str, &str)] = &[
        ("speed = 1", "speed"),
        ("[ball]\nx = \"left\"\ny = 0", "x = \"left\""),
        ("[ball]\nx = [1, 2, 3]\ny = 0", "x = [1, 2, 3]"),
        ("[ball]\nx = [2, 1]\ny = 0", "`ball.x`"),
        ("[[robot]]\nside = \"own\"\nplayer = 4\nx = 0\ny = 0", "`robot[0].player`"),
        (
            "[[robot]]\nside = \"own\"\nplayer = 1\nx = 0\ny = 0\n[[robot]]\nside = \"own\"\nplayer = 1\nx = 1\ny = 0",
            "`robot[1].player`",
        ),
        ("[[robot]]\nside = \"ours\"\nplayer = 1\nx = 0\ny = 0", "side = \"ours\""),
        ("[[robot]]\nside = \"own\"\nplayer = 1\nx = 0\ny = 0\nheading = \"left\"", "heading"),
        ("[state]\nphase = \"corner_kick\"", "`state.taken_by`"),
        ("[state]\ntaken_by = \"own\"", "`state.taken_by`"),
        ("[state]\nphase = \"penalty\"", "phase = \"penalty\""),
        ("[state]\nhalf = 3", "`state.half`"),
        ("[state]\nelapsed = 1\ntime_left = 2", "`state.time_left`"),
        ("[state]\nelapsed = -1", "`state.elapsed`"),
        ("[state]\nlast_touch = { side = \"own\", player = 2 }", "`state.last_touch`"),
        ("duration = 0", "`duration`"),
        ("[[end]]\nwhen = \"goal\"\noutcome = \"success\"", "`end[0].when`"),
        ("[[end]]\nwhen = \"region\"\nx = [1, 2]\noutcome = \"success\"", "`end[0].y`"),
        ("[[end]]\nwhen = \"time_up\"\nx = [1, 2]\noutcome = \"success\"", "`end[0].x`"),
        ("[[end]]\nwhen = \"time_up\"\noutcome = \"win\"", "outcome = \"win\""),
    ];
    for (text, field) in cases {
        let e = err(text);
        assert!(e.contains(field), "{text:?}: {e}");
    }
}

#[test]
fn a_file_that_does_not_fit_the_match_names_the_field() {
    let check = |text: &str| {
        Scenario::from_toml(text, None)
            .unwrap()
            .check(&cfg())
            .unwrap_err()
            .to_string()
    };
    assert!(check("[ball]\nx = [2.0, 3.5]\ny = 0").contains("`ball.x` reaches 3.5"));
    assert!(
        check("[[robot]]\nside = \"own\"\nplayer = 0\nx = 0\ny = 2.6").contains("`robot[0].y`")
    );
    assert!(check("[state]\nelapsed = 300").contains("`state.elapsed`"));
    assert!(check("[state]\ntime_left = 0").contains("`state.time_left`"));
    let mut one_half = cfg();
    one_half.rules.halves = 1;
    let second = Scenario::from_toml("[state]\nhalf = 2", None).unwrap();
    assert!(second
        .check(&one_half)
        .unwrap_err()
        .to_string()
        .contains("`state.half`"));
}

#[test]
fn starts_exactly_where_the_file_says_for_either_colour() {
    let s = Scenario::from_toml(EMPTY_GOAL, None).unwrap();
    for own in Team::BOTH {
        let m = Match::with_scenario(&cfg(), 7, &s, own).unwrap();
        let sign = own.direction();
        let snap = m.sim().snapshot();
        let [bx, by, _] = snap.ball.pos;
        assert!((bx - sign * 2.0).abs() < 1e-3 && (by - sign * 0.3).abs() < 1e-3);
        assert!(
            (snap.ball.vel[0] - sign * 1.0).abs() < 1e-3,
            "{:?}",
            snap.ball.vel
        );
        let kicker = RobotId::new(own, 1).unwrap().index();
        let r = snap.robots[kicker];
        assert!((r.pos[0] - sign * 1.75).abs() < 1e-3, "{:?}", r.pos);
        assert!((r.pos[1] - sign * 0.3).abs() < 1e-3, "{:?}", r.pos);
        let facing = if own == Team::Blue {
            0.0
        } else {
            std::f32::consts::PI
        };
        assert!(wrap(r.heading - facing).abs() < 1e-3, "{}", r.heading);
        let keeper = snap.robots[RobotId::new(own.other(), 0).unwrap().index()];
        assert!((keeper.pos[0] - sign * 2.7).abs() < 1e-3);
        assert!(keeper.pos[1].abs() <= 0.5 + 1e-3);
        // Everybody else is out of play, off the pitch.
        for robot in RobotId::all() {
            let listed = robot.index() == kicker || robot == RobotId::new(own.other(), 0).unwrap();
            assert_eq!(m.is_out_of_play(robot), !listed, "{robot:?}");
            if !listed {
                let p = snap.robots[robot.index()].pos;
                assert!(p[1].abs() > 2.25 + 1.0, "{robot:?} at {p:?}");
            }
        }
        assert_eq!(m.tick(), Tick::ZERO);
        assert_eq!(m.set_play(), None);
    }
}

fn wrap(a: f32) -> f32 {
    crate::rules::wrap_angle(a)
}

#[test]
fn ranges_are_drawn_from_the_seed() {
    let s = Scenario::from_toml(EMPTY_GOAL, None).unwrap();
    let keeper_y = |seed| {
        let m = Match::with_scenario(&cfg(), seed, &s, Team::Blue).unwrap();
        m.sim().snapshot().robots[4].pos[1]
    };
    assert_eq!(keeper_y(3).to_bits(), keeper_y(3).to_bits());
    let ys: Vec<f32> = (0..8).map(keeper_y).collect();
    assert!(ys.windows(2).any(|w| w[0] != w[1]), "{ys:?}");
    assert!(ys.iter().all(|y| y.abs() <= 0.5 + 1e-3), "{ys:?}");
}

/// `ball.direction` turns the robots placed from the ball (offsets and
/// numeric headings) and the ball's velocity, as one rigid group; robots
/// placed from the centre stay where they are.
#[test]
fn the_direction_turns_the_robots_placed_from_the_ball() {
    let text = r#"
[ball]
x = 0.5
y = 0.2
vx = 1.0
direction = [-1.0, 1.0]

[[robot]]
side = "own"
player = 1
from = "ball"
x = -0.2
y = 0.0
heading = 0.0

[[robot]]
side = "own"
player = 2
from = "ball"
x = 1.5
y = 0.0
heading = "ball"

[[robot]]
side = "opponent"
player = 0
x = 2.6
y = 0.0
heading = 3.0
"#;
    let s = Scenario::from_toml(text, None).unwrap();
    let straight = Scenario::from_toml(&text.replace("direction = [-1.0, 1.0]", ""), None).unwrap();
    let mut dirs = Vec::new();
    for seed in 0..12 {
        let start = s.draw(&cfg(), seed, Team::Blue);
        let kicker = start.robots[1].unwrap();
        let receiver = start.robots[2].unwrap();
        // The kicker 0.2 m behind the ball along the direction, facing it.
        let d = kicker.heading;
        assert!((-1.0 - 1e-6..=1.0 + 1e-6).contains(&d), "{d}");
        assert!(
            (kicker.x - (0.5 - 0.2 * d.cos())).abs() < 1e-5,
            "{kicker:?}"
        );
        assert!(
            (kicker.y - (0.2 - 0.2 * d.sin())).abs() < 1e-5,
            "{kicker:?}"
        );
        // The receiver 1.5 m on in the kicker's line, facing the ball.
        assert!(
            (receiver.x - (0.5 + 1.5 * d.cos())).abs() < 1e-5,
            "{receiver:?}"
        );
        assert!(
            (receiver.y - (0.2 + 1.5 * d.sin())).abs() < 1e-5,
            "{receiver:?}"
        );
        assert!(wrap(receiver.heading - (d + std::f32::consts::PI)).abs() < 1e-4);
        let (vx, vy) = start.ball_velocity;
        assert!((vx - d.cos()).abs() < 1e-5 && (vy - d.sin()).abs() < 1e-5);
        // From the centre: untouched.
        assert_eq!(
            start.robots[4],
            straight.draw(&cfg(), seed, Team::Blue).robots[4]
        );
        dirs.push(d);
    }
    assert!(dirs.windows(2).any(|w| w[0] != w[1]), "{dirs:?}");
    // Without a direction nothing is turned (and nothing more is drawn).
    let plain = straight.draw(&cfg(), 3, Team::Blue);
    assert_eq!(plain.robots[1].unwrap().heading, 0.0);
    assert_eq!(plain.ball_velocity, (1.0, 0.0));
    assert!(err("[ball]\nx = 0\ny = 0\ndirection = [1.0, 0.0]\n").contains("ball.direction"));
}

#[test]
fn absent_robots_stay_out_of_play() {
    let s = Scenario::from_toml(EMPTY_GOAL, None).unwrap();
    let mut m = Match::with_scenario(&cfg(), 1, &s, Team::Blue).unwrap();
    let before = m.sim().snapshot().robots[6].pos;
    for _ in 0..30 {
        let events = m.step(&[Action::Forward; ROBOTS]).to_vec();
        assert!(
            !events.iter().any(|e| matches!(e, Event::RobotOut { .. })),
            "{events:?}"
        );
    }
    assert_eq!(m.sim().snapshot().robots[6].pos, before);
}

#[test]
fn the_referee_state_is_the_file_s() {
    let text = r#"
[ball]
x = 2.9
y = 2.2
[[robot]]
side = "own"
player = 2
x = 2.6
y = 1.9
heading = "ball"
[[robot]]
side = "opponent"
player = 1
x = 2.7
y = 2.0
[[robot]]
side = "opponent"
player = 3
x = 0.0
y = 0.0
fallen = true
[state]
score = { own = 2, opponent = 1 }
half = 2
elapsed = 30.0
phase = "corner_kick"
taken_by = "own"
last_touch = { side = "opponent", player = 1 }
"#;
    let s = Scenario::from_toml(text, None).unwrap();
    let c = cfg();
    let m = Match::with_scenario(&c, 1, &s, Team::Red).unwrap();
    assert_eq!(m.half(), 2);
    assert_eq!(m.tick().get(), 3000 + 300);
    assert_eq!((m.score().red, m.score().blue), (2, 1));
    let (kind, team, _) = m.set_play().unwrap();
    assert_eq!((kind, team), (SetPlayKind::CornerKick, Team::Red));
    // The opponent inside the keep-out circle went out to its edge.
    let snap = m.sim().snapshot();
    let [bx, by, _] = snap.ball.pos;
    let o = snap.robots[RobotId::new(Team::Blue, 1).unwrap().index()].pos;
    assert!((o[0] - bx).hypot(o[1] - by) >= c.rules.set_play_distance - 1e-3);
    let lying = RobotId::new(Team::Blue, 3).unwrap();
    assert!(m.is_down(lying));
    assert_eq!(m.up_at(lying).unwrap().get(), 3300 + 50);
    assert_eq!(crate::rules::last_touch(snap), RobotId::new(Team::Blue, 1));
    let obs = m.observe(Team::Red, 2);
    assert_eq!(obs.half, 2);
    assert!((obs.time_left - 270.0).abs() < 1e-3);
}

#[test]
fn the_judge_sees_a_goal_and_time_up() {
    let s = Scenario::from_toml(EMPTY_GOAL, None).unwrap();
    let c = cfg();
    for own in Team::BOTH {
        let mut m = Match::with_scenario(&c, 2, &s, own).unwrap();
        let judge = s.judge(&c, own, m.tick());
        let mut ending = None;
        while ending.is_none() {
            let events = m.step(&[Action::Stay; ROBOTS]).to_vec();
            ending = judge.check(&m, &events);
        }
        let e = ending.unwrap();
        assert_eq!((e.kind, e.success), (EndKind::GoalFor, true), "{own:?}");
        assert!(e.ticks < 40, "{e:?}");
    }
    let still = Scenario::from_toml("duration = 2.5\n[ball]\nx = 1\ny = 0", None).unwrap();
    let mut m = Match::with_scenario(&c, 2, &still, Team::Blue).unwrap();
    let judge = still.judge(&c, Team::Blue, m.tick());
    let mut ticks = 0;
    loop {
        let events = m.step(&[Action::Stay; ROBOTS]).to_vec();
        ticks += 1;
        if let Some(e) = judge.check(&m, &events) {
            assert_eq!((e.kind, e.success, e.ticks), (EndKind::TimeUp, false, 25));
            break;
        }
    }
    assert_eq!(ticks, 25);
}

#[test]
fn half_time_ends_a_play_with_a_duration_and_not_one_without() {
    let c = cfg();
    let play = |text: &str, ticks: usize| {
        let s = Scenario::from_toml(text, None).unwrap();
        let mut m = Match::with_scenario(&c, 4, &s, Team::Blue).unwrap();
        let judge = s.judge(&c, Team::Blue, m.tick());
        for _ in 0..ticks {
            let events = m.step(&[Action::Stay; ROBOTS]).to_vec();
            if let Some(e) = judge.check(&m, &events) {
                return Some((e, m.tick().get()));
            }
        }
        None
    };
    let (e, tick) = play("duration = 60\n[state]\nelapsed = 299", 20).unwrap();
    assert_eq!((e.kind, e.ticks, tick), (EndKind::TimeUp, 10, 3000));
    assert_eq!(play("[state]\nelapsed = 299", 20), None);
    let (e, tick) = play("[state]\nhalf = 2\ntime_left = 1", 20).unwrap();
    assert_eq!((e.kind, e.success, tick), (EndKind::TimeUp, false, 6000));
}

/// A `busy` robot starts in the recovery of a kick: it observes `busy`,
/// does not move when told to walk or kick until the recovery is over, the
/// ball stays where it was, and then it walks. `busy` with `fallen` is
/// refused, naming the field.
#[test]
fn a_busy_robot_starts_in_a_kicks_recovery() {
    let text = r#"
name = "busy"
[ball]
x = 0.0
y = 0.0
[[robot]]
side = "own"
player = 1
x = -0.2
y = 0.0
heading = 0.0
busy = true
[[robot]]
side = "own"
player = 2
x = -1.0
y = 1.0
heading = 0.0
"#;
    let s = Scenario::from_toml(text, None).unwrap();
    let c = cfg();
    for own in [Team::Blue, Team::Red] {
        let mut m = Match::with_scenario(&c, 3, &s, own).unwrap();
        let busy = RobotId::new(own, 1).unwrap();
        let free = RobotId::new(own, 2).unwrap();
        assert!(m.observe(own, 1).me().busy);
        assert!(!m.observe(own, 2).me().busy);
        let start = m.sim().snapshot().robots[busy.index()].pos;
        let ball = m.sim().snapshot().ball.pos;
        let recovery_ticks = (c.sim.kick_recovery * c.control_hz).ceil() as u64;
        let mut walk = [Action::Stay; ROBOTS];
        walk[busy.index()] = Action::Shoot;
        walk[free.index()] = Action::Forward;
        let mut ticks_busy = 0;
        while m.observe(own, 1).me().busy {
            m.step(&walk);
            ticks_busy += 1;
            assert!(ticks_busy <= recovery_ticks, "busy for {ticks_busy} ticks");
        }
        assert!(ticks_busy >= 1);
        let now = m.sim().snapshot().robots[busy.index()].pos;
        assert!(
            (now[0] - start[0]).hypot(now[1] - start[1]) < 0.01,
            "{start:?} {now:?}"
        );
        let b = m.sim().snapshot().ball.pos;
        assert!(
            (b[0] - ball[0]).hypot(b[1] - ball[1]) < 1e-3,
            "the ball was kicked"
        );
        // Free now: it walks.
        walk[busy.index()] = Action::Forward;
        for _ in 0..10 {
            m.step(&walk);
        }
        let later = m.sim().snapshot().robots[busy.index()].pos;
        assert!(
            (later[0] - now[0]).hypot(later[1] - now[1]) > 0.05,
            "{now:?} {later:?}"
        );
    }
    let both = text.replace("busy = true", "busy = true\nfallen = true");
    let err = Scenario::from_toml(&both, None)
        .and_then(|s| s.check(&c).map(|_| s))
        .unwrap_err()
        .to_string();
    assert!(err.contains("robot[0].busy"), "{err}");
}
