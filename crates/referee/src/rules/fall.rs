//! Falls (the paper's fall detection and `getup`): a robot has fallen when
//! the sim says it lost its balance (`RobotState::fallen`: its torso tilted
//! past the sim's `fall_tilt`), or its torso drops under the height threshold,
//! or tilts past the tilt threshold. It lies, as an obstacle and without
//! acting, for the stand-up cost, then is stood up where it lies.
//!
//! The sim switches a robot's controller off when it falls, and also while
//! it topples from a stumble, which is not yet a fall: the stumble ends in a
//! fall once the tilt passes `fall_tilt`, or, if the robot catches itself,
//! gives the controller back within a second. So every robot the sim leaves
//! without its controller is counted down here within a second, and stood
//! up by this rule (the sim's fall lasts until `stand_up` or a placement).

use naosoccer_proto::{Event, RobotId, Tick, ROBOTS};
use naosoccer_sim::Snapshot;

use super::outcome::{Command, Outcome};

#[derive(Debug, Clone)]
pub struct FallRule {
    height: f32,
    tilt: f32,
    standup_ticks: u64,
    /// For each lying robot, the tick at which it gets up.
    up_at: [Option<Tick>; ROBOTS],
}

impl FallRule {
    pub fn new(height: f32, tilt: f32, standup_ticks: u64) -> FallRule {
        FallRule {
            height,
            tilt,
            standup_ticks,
            up_at: [None; ROBOTS],
        }
    }

    /// Whether a robot is lying on the pitch, as the referee counts it.
    pub fn is_down(&self, robot: usize) -> bool {
        self.up_at.get(robot).is_some_and(Option::is_some)
    }

    /// `is_down` for every robot.
    pub fn down(&self) -> [bool; ROBOTS] {
        self.up_at.map(|u| u.is_some())
    }

    /// The tick at which a lying robot will be stood up.
    pub fn up_at(&self, robot: usize) -> Option<Tick> {
        self.up_at.get(robot).copied().flatten()
    }

    /// Forgets every fall: after a kick-off everybody stands in place.
    pub fn clear(&mut self) {
        self.up_at = [None; ROBOTS];
    }

    /// Counts robot `robot` as lying from `tick` on, to be stood up after
    /// the stand-up cost (a staged fall: no `Fall` event).
    pub fn lay(&mut self, robot: usize, tick: Tick) {
        if let Some(u) = self.up_at.get_mut(robot) {
            *u = Some(tick + self.standup_ticks);
        }
    }

    /// Forgets one robot's fall (it was reset upright).
    pub fn clear_robot(&mut self, robot: usize) {
        if let Some(u) = self.up_at.get_mut(robot) {
            *u = None;
        }
    }

    /// Whether the snapshot shows robot `i` fallen: the sim's fall, or the
    /// referee's own thresholds.
    pub fn has_fallen(&self, snap: &Snapshot, i: usize) -> bool {
        let r = &snap.robots[i];
        r.fallen || r.pos[2] < self.height || r.tilt > self.tilt
    }

    pub fn check(&mut self, snap: &Snapshot, tick: Tick, out: &mut Outcome) {
        for i in 0..ROBOTS {
            let Some(robot) = RobotId::from_index(i) else {
                continue;
            };
            match self.up_at[i] {
                Some(up) if tick >= up => {
                    self.up_at[i] = None;
                    out.events.push(Event::GetUp { tick, robot });
                    out.commands.push(Command::StandUp { robot });
                }
                Some(_) => {}
                None if self.has_fallen(snap, i) => {
                    self.up_at[i] = Some(tick + self.standup_ticks);
                    out.events.push(Event::Fall { tick, robot });
                }
                None => {}
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rules::testing::snapshot;

    #[test]
    fn low_torso_falls_and_gets_up_after_the_cost() {
        let mut rule = FallRule::new(0.2, 1.0, 30);
        let mut s = snapshot();
        let mut out = Outcome::default();
        rule.check(&s, Tick::new(10), &mut out);
        assert!(out.events.is_empty());
        s.robots[2].pos[2] = 0.1;
        rule.check(&s, Tick::new(11), &mut out);
        let robot = RobotId::from_index(2).unwrap();
        assert_eq!(
            out.events,
            vec![Event::Fall {
                tick: Tick::new(11),
                robot
            }]
        );
        assert!(rule.is_down(2));
        out.clear();
        for t in 12..41 {
            rule.check(&s, Tick::new(t), &mut out);
        }
        assert!(out.events.is_empty(), "{:?}", out.events);
        rule.check(&s, Tick::new(41), &mut out);
        assert_eq!(
            out.events,
            vec![Event::GetUp {
                tick: Tick::new(41),
                robot
            }]
        );
        assert_eq!(out.commands, vec![Command::StandUp { robot }]);
        assert!(!rule.is_down(2));
    }

    /// Issue 12: the sim's fall counts on its own, below the referee's
    /// thresholds (the sim's `fall_tilt` is the lower), so a robot whose
    /// controller the sim switched off for a fall is always counted down.
    #[test]
    fn the_sims_fall_alone_is_a_fall() {
        let mut rule = FallRule::new(0.2, 0.5, 30);
        let mut s = snapshot();
        s.robots[1].fallen = true;
        s.robots[1].tilt = 0.4;
        let mut out = Outcome::default();
        rule.check(&s, Tick::new(7), &mut out);
        let robot = RobotId::from_index(1).unwrap();
        assert_eq!(
            out.events,
            vec![Event::Fall {
                tick: Tick::new(7),
                robot
            }]
        );
        assert!(rule.is_down(1));
    }

    #[test]
    fn tilt_alone_is_a_fall() {
        let mut rule = FallRule::new(0.2, 1.0, 30);
        let mut s = snapshot();
        s.robots[6].tilt = 1.2;
        let mut out = Outcome::default();
        rule.check(&s, Tick::new(3), &mut out);
        assert_eq!(
            out.events,
            vec![Event::Fall {
                tick: Tick::new(3),
                robot: RobotId::from_index(6).unwrap()
            }]
        );
    }
}
