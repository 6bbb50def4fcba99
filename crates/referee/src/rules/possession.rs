//! Possession, the paper's `if_c`: robot n controls the ball when the ball is
//! closer than `b_d` and lies within `b_rad` of its heading. At most one robot
//! (so one team) controls it at a time: the closest candidate wins.

use naosoccer_proto::{RobotId, ROBOTS};
use naosoccer_sim::Snapshot;

use super::field::wrap_angle;

#[derive(Debug, Clone, Copy)]
pub struct PossessionRule {
    b_d: f32,
    b_rad: f32,
}

impl PossessionRule {
    pub fn new(b_d: f32, b_rad: f32) -> PossessionRule {
        PossessionRule { b_d, b_rad }
    }

    /// Distance to the ball if robot `i` meets the control conditions.
    pub fn candidate(&self, snap: &Snapshot, i: usize) -> Option<f32> {
        let r = &snap.robots[i];
        let dx = snap.ball.pos[0] - r.pos[0];
        let dy = snap.ball.pos[1] - r.pos[1];
        let d = dx.hypot(dy);
        if d >= self.b_d {
            return None;
        }
        let dtheta = wrap_angle(dy.atan2(dx) - r.heading);
        (dtheta.abs() < self.b_rad).then_some(d)
    }

    /// The controller: the closest candidate among robots that are not lying
    /// down; on an exact tie the lower robot index, so the answer never
    /// depends on anything but the snapshot.
    pub fn controller(&self, snap: &Snapshot, down: &[bool; ROBOTS]) -> Option<RobotId> {
        let mut best: Option<(f32, usize)> = None;
        for (i, &lying) in down.iter().enumerate() {
            if lying {
                continue;
            }
            if let Some(d) = self.candidate(snap, i) {
                if best.is_none_or(|(bd, _)| d < bd) {
                    best = Some((d, i));
                }
            }
        }
        best.and_then(|(_, i)| RobotId::from_index(i))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rules::testing::snapshot;
    use std::f32::consts::PI;

    #[test]
    fn close_and_facing_controls() {
        let rule = PossessionRule::new(0.3, 0.4);
        let mut s = snapshot();
        s.ball.pos = [1.0, 1.0, 0.05];
        s.robots[1].pos = [0.8, 1.0, 0.3];
        s.robots[1].heading = 0.1;
        assert_eq!(rule.controller(&s, &[false; 8]), RobotId::from_index(1));
        // Facing away: no control.
        s.robots[1].heading = PI;
        assert_eq!(rule.controller(&s, &[false; 8]), None);
        // Too far.
        s.robots[1].heading = 0.0;
        s.robots[1].pos = [0.6, 1.0, 0.3];
        assert_eq!(rule.controller(&s, &[false; 8]), None);
    }

    #[test]
    fn closest_candidate_wins_and_lying_robots_never_control() {
        let rule = PossessionRule::new(0.3, 0.4);
        let mut s = snapshot();
        s.ball.pos = [0.0, 0.0, 0.05];
        s.robots[2].pos = [-0.25, 0.0, 0.3];
        s.robots[2].heading = 0.0;
        s.robots[6].pos = [0.2, 0.0, 0.3];
        s.robots[6].heading = PI;
        assert_eq!(rule.controller(&s, &[false; 8]), RobotId::from_index(6));
        let mut down = [false; 8];
        down[6] = true;
        assert_eq!(rule.controller(&s, &down), RobotId::from_index(2));
    }
}
