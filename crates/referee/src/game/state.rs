//! A state set from outside the play (protocol 1.5's `set_state`, as
//! rcssserver's trainer moves things): the ball and any robots put where
//! asked between two ticks, the referee's state made consistent with it.

use naosoccer_proto::{RobotId, StateChange, ROBOTS};

use super::Match;
use crate::rules::wrap_angle;

/// The fastest a `set_state` may set the ball rolling, m/s along each
/// axis (a kick gives it about 3 m/s).
pub const MAX_BALL_SPEED: f32 = 10.0;

/// Why a state change was refused; the match is then unchanged.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum StateError {
    /// A field of the change is out of range; `field` names it as the
    /// protocol spells it (`ball.x`, `robots[1].robot`).
    #[error("`{field}` {reason}")]
    Invalid { field: String, reason: String },
    #[error("the match has finished")]
    Finished,
}

fn invalid(field: impl Into<String>, reason: impl Into<String>) -> StateError {
    StateError::Invalid {
        field: field.into(),
        reason: reason.into(),
    }
}

impl Match {
    /// Whether [`Match::set_state`] would take `change`: the ball within
    /// the field lines and at most [`MAX_BALL_SPEED`] along each axis,
    /// robots 0..=7, each at most once, in play (not absent from the
    /// match's scenario), within the field lines plus half the ground
    /// margin, every number finite; at least the ball or one robot.
    pub fn check_state(&self, change: &StateChange) -> Result<(), StateError> {
        if self.finished {
            return Err(StateError::Finished);
        }
        if change.ball.is_none() && change.robots.is_empty() {
            return Err(invalid(
                "ball",
                "and `robots` are both missing: nothing to set",
            ));
        }
        let sim = &self.cfg.sim;
        let (hx, hy) = (sim.field_length / 2.0, sim.field_width / 2.0);
        let within = |v: f32, half: f32, field: String, what: &str| {
            if v.is_finite() && v.abs() <= half {
                Ok(())
            } else {
                Err(invalid(field, format!("is {v}: {what}, within +-{half} m")))
            }
        };
        if let Some(b) = &change.ball {
            let what = "the ball goes within the field lines";
            within(b.x, hx, "ball.x".into(), what)?;
            within(b.y, hy, "ball.y".into(), what)?;
            for (v, field) in [(b.vx, "ball.vx"), (b.vy, "ball.vy")] {
                if !(v.is_finite() && v.abs() <= MAX_BALL_SPEED) {
                    return Err(invalid(
                        field,
                        format!("is {v}: m/s, within +-{MAX_BALL_SPEED}"),
                    ));
                }
            }
        }
        let m = sim.ground_margin / 2.0;
        let what = "a robot goes within the field lines plus half the ground margin";
        let mut seen = [false; ROBOTS];
        for (k, r) in change.robots.iter().enumerate() {
            let field = |name: &str| format!("robots[{k}].{name}");
            let Some(robot) = usize::try_from(r.robot).ok().and_then(RobotId::from_index) else {
                return Err(invalid(
                    field("robot"),
                    format!(
                        "is {}: robots are 0 to 7 (blue players 0 to 3, then red players 0 to 3)",
                        r.robot
                    ),
                ));
            };
            if std::mem::replace(&mut seen[robot.index()], true) {
                return Err(invalid(
                    field("robot"),
                    format!("is {}: the robot is listed twice", r.robot),
                ));
            }
            if self.off[robot.index()] {
                return Err(invalid(
                    field("robot"),
                    format!(
                        "is {}: the robot is out of play (absent from the match's scenario)",
                        r.robot
                    ),
                ));
            }
            within(r.x, hx + m, field("x"), what)?;
            within(r.y, hy + m, field("y"), what)?;
            if let Some(h) = r.heading {
                if !h.is_finite() {
                    return Err(invalid(field("heading"), format!("is {h}: radians")));
                }
            }
        }
        Ok(())
    }

    /// Sets the state between two ticks: the match is then at the same
    /// tick, and the next [`Match::step`] plays it from the new state and
    /// reports [`Event::StateSet`](naosoccer_proto::Event::StateSet) first
    /// among its events. Refused (the match unchanged) when
    /// [`Match::check_state`] refuses the change.
    ///
    /// - The ball (if given) goes exactly where asked, at rest or rolling
    ///   at (`vx`, `vy`); robots whose body comes within 2 cm of it are
    ///   moved aside as for a set play's ball. Nobody has touched it since.
    /// - Then the robots, in robot index order: each stands upright, facing
    ///   its heading (the one it had when none is given), at the free spot
    ///   nearest the asked one, given where every other body is at that
    ///   moment (the placement of restarts and scenarios: 2 cm from every
    ///   other body, rings 5 cm apart); one asked `fallen` lies exactly
    ///   there, overlapping or not, and gets up after the stand-up time.
    /// - A set play or kick-off in progress ends (and with it the kick-off
    ///   rule and the goal's restart phase); no pass is in progress;
    ///   possession follows from the new positions. A robot that lay and
    ///   now stands gets a `get_up` event after the `state_set`.
    pub fn set_state(&mut self, change: &StateChange) -> Result<(), StateError> {
        self.check_state(change)?;
        let tick = self.tick;
        let was_down = self.fall.down();
        if let Some(b) = &change.ball {
            let moved = self.sim.place_ball_exact(b.x, b.y);
            for (i, moved) in moved.into_iter().enumerate() {
                if moved {
                    self.fall.clear_robot(i);
                }
            }
            if b.vx != 0.0 || b.vy != 0.0 {
                self.sim.set_ball_velocity(b.vx, b.vy);
            }
            self.sim.set_last_touch(None);
        }
        let mut robots: Vec<_> = change.robots.iter().collect();
        robots.sort_by_key(|r| r.robot);
        for r in robots {
            let i = r.robot as usize;
            let heading = match r.heading {
                Some(h) => wrap_angle(h),
                None => self.sim.snapshot().robots[i].heading,
            };
            if r.fallen {
                self.sim.lay_down(i, r.x, r.y, heading);
                self.fall.lay(i, tick);
            } else {
                self.sim.place_robot(i, r.x, r.y, heading);
                self.fall.clear_robot(i);
            }
        }
        self.set_play.clear();
        self.restart.clear();
        self.pass.reset();
        let down = self.fall.down();
        self.controller = self.possession.controller(self.sim.snapshot(), &down);
        self.announce
            .push(naosoccer_proto::Event::StateSet { tick });
        for robot in RobotId::all() {
            if was_down[robot.index()] && !down[robot.index()] {
                self.announce
                    .push(naosoccer_proto::Event::GetUp { tick, robot });
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use naosoccer_proto::{
        Action, BallPlacement, Event, RobotPlacement, SetPlayKind, StateChange, Team, Tick,
    };

    use super::*;
    use crate::{MatchConfig, Scenario};

    fn ball(x: f32, y: f32) -> BallPlacement {
        BallPlacement {
            x,
            y,
            vx: 0.0,
            vy: 0.0,
        }
    }

    fn robot(robot: u64, x: f32, y: f32) -> RobotPlacement {
        RobotPlacement {
            robot,
            x,
            y,
            heading: Some(0.5),
            fallen: false,
        }
    }

    fn new_match() -> Match {
        Match::new(&MatchConfig::default(), 3).unwrap()
    }

    const STAY: [Action; ROBOTS] = [Action::Stay; ROBOTS];

    fn xy(m: &Match, i: usize) -> (f32, f32) {
        let p = m.sim().snapshot().robots[i].pos;
        (p[0], p[1])
    }

    #[test]
    fn the_ball_and_robots_go_where_asked_and_the_kick_off_ends() {
        let mut m = new_match();
        assert!(m.set_play().is_some(), "the kick-off is in progress");
        m.step(&STAY);
        let change = StateChange {
            ball: Some(ball(1.5, -0.5)),
            robots: vec![robot(6, -1.0, 1.0), robot(1, 1.2, -0.5)],
        };
        m.set_state(&change).unwrap();
        assert_eq!(m.tick(), Tick::new(1), "no tick played");
        let b = m.sim().snapshot().ball;
        assert_eq!((b.pos[0], b.pos[1]), (1.5, -0.5));
        assert_eq!(b.vel[0], 0.0);
        assert_eq!(xy(&m, 6), (-1.0, 1.0));
        // Robot 1 was asked just behind the ball: it stands clear of it.
        let (x, y) = xy(&m, 1);
        assert!((x - 1.2).abs() < 0.3 && (y + 0.5).abs() < 0.3, "{x} {y}");
        assert!((m.sim().snapshot().robots[6].heading - 0.5).abs() < 1e-6);
        assert_eq!(m.set_play(), None, "the kick-off ended");
        // Possession follows the new positions; the last touch is nobody's.
        let snap = m.sim().snapshot();
        assert!(snap.robots.iter().all(|r| r.last_ball_touch_step.is_none()));
        let events = m.step(&STAY).to_vec();
        assert_eq!(
            events.first(),
            Some(&Event::StateSet { tick: Tick::new(1) })
        );
        assert_eq!(m.set_play(), None);
    }

    #[test]
    fn a_robot_placed_onto_another_goes_to_the_nearest_free_spot() {
        let mut m = new_match();
        let (x0, y0) = xy(&m, 5);
        let change = StateChange {
            ball: None,
            robots: vec![robot(2, x0, y0)],
        };
        m.set_state(&change).unwrap();
        let (x, y) = xy(&m, 2);
        let d = (x - x0).hypot(y - y0);
        assert!(d > 0.05 && d < 0.6, "moved aside by {d}");
        assert_eq!(xy(&m, 5), (x0, y0), "the robot standing there stays");
    }

    #[test]
    fn fallen_robots_lie_and_get_up_and_standing_them_up_is_announced() {
        let mut m = new_match();
        let lie = StateChange {
            ball: None,
            robots: vec![RobotPlacement {
                fallen: true,
                ..robot(3, 0.5, 1.5)
            }],
        };
        m.set_state(&lie).unwrap();
        let r3 = RobotId::from_index(3).unwrap();
        assert!(m.is_down(r3));
        assert_eq!(
            m.up_at(r3),
            Some(Tick::ZERO + (5.0 * m.config().control_hz) as u64)
        );
        m.step(&STAY);
        assert!(m.is_down(r3), "still lying");
        let stand = StateChange {
            ball: None,
            robots: vec![robot(3, 0.5, 1.5)],
        };
        m.set_state(&stand).unwrap();
        assert!(!m.is_down(r3));
        let events = m.step(&STAY).to_vec();
        assert_eq!(
            &events[..2],
            [
                Event::StateSet { tick: Tick::new(1) },
                Event::GetUp {
                    tick: Tick::new(1),
                    robot: r3
                }
            ]
        );
    }

    #[test]
    fn bad_changes_name_the_field_and_change_nothing() {
        let mut m = new_match();
        let before = m.state_hash();
        let cases: &[(StateChange, &str)] = &[
            (StateChange::default(), "`ball`"),
            (
                StateChange {
                    ball: Some(ball(3.5, 0.0)),
                    robots: vec![],
                },
                "`ball.x` is 3.5",
            ),
            (
                StateChange {
                    ball: Some(BallPlacement {
                        vy: 11.0,
                        ..ball(0.0, 0.0)
                    }),
                    robots: vec![],
                },
                "`ball.vy`",
            ),
            (
                StateChange {
                    ball: Some(ball(f32::NAN, 0.0)),
                    robots: vec![],
                },
                "`ball.x`",
            ),
            (
                StateChange {
                    ball: None,
                    robots: vec![robot(8, 0.0, 0.0)],
                },
                "`robots[0].robot` is 8",
            ),
            (
                StateChange {
                    ball: None,
                    robots: vec![robot(1, 0.0, 0.0), robot(1, 1.0, 0.0)],
                },
                "`robots[1].robot` is 1: the robot is listed twice",
            ),
            (
                StateChange {
                    ball: Some(ball(0.0, 0.0)),
                    robots: vec![robot(0, 0.0, 2.6)],
                },
                "`robots[0].y` is 2.6",
            ),
            (
                StateChange {
                    ball: None,
                    robots: vec![RobotPlacement {
                        heading: Some(f32::INFINITY),
                        ..robot(0, 0.0, 0.0)
                    }],
                },
                "`robots[0].heading`",
            ),
        ];
        for (change, want) in cases {
            let e = m.set_state(change).unwrap_err().to_string();
            assert!(e.starts_with(want), "{e} (wanted {want})");
        }
        assert_eq!(m.state_hash(), before);
        assert!(m.set_play().is_some(), "the kick-off is still on");
    }

    #[test]
    fn absent_robots_and_finished_matches_are_refused() {
        let text = "[[robot]]\nside = \"own\"\nplayer = 1\nx = 0\ny = 0\n";
        let s = Scenario::from_toml(text, None).unwrap();
        let mut m = Match::with_scenario(&MatchConfig::default(), 1, &s, Team::Red).unwrap();
        let change = StateChange {
            ball: None,
            robots: vec![robot(0, 0.0, 0.0)],
        };
        let e = m.set_state(&change).unwrap_err().to_string();
        assert!(e.contains("out of play"), "{e}");
        // Red's player 1 is the scenario's own robot: in play.
        let ok = StateChange {
            ball: None,
            robots: vec![robot(5, 1.0, 1.0)],
        };
        m.set_state(&ok).unwrap();

        let cfg = MatchConfig {
            minutes: 0.05,
            ..MatchConfig::default()
        };
        let mut m = Match::new(&cfg, 1).unwrap();
        while !m.is_finished() {
            m.step(&STAY);
        }
        assert_eq!(m.set_state(&ok), Err(StateError::Finished));
    }

    /// The same changes at the same ticks give the same match, bit for bit;
    /// and a set play awarded after a state set is played as usual.
    #[test]
    fn set_states_are_deterministic() {
        let play = || {
            let mut m = new_match();
            let mut hashes = Vec::new();
            for t in 0..40 {
                if t == 5 || t == 17 {
                    let change = StateChange {
                        ball: Some(BallPlacement {
                            x: 2.8,
                            y: 2.0,
                            vx: 0.0,
                            vy: 2.0,
                        }),
                        robots: vec![robot(4, 0.0, 0.0)],
                    };
                    m.set_state(&change).unwrap();
                }
                m.step(&STAY);
                hashes.push(m.state_hash());
            }
            (hashes, m.stats())
        };
        let (a, stats) = play();
        assert_eq!(a, play().0);
        // The ball rolled over the touch line: a kick-in after each set.
        assert_eq!(stats.blue.kick_ins + stats.red.kick_ins, 2, "{stats:?}");
        let _ = SetPlayKind::KickIn;
    }
}
