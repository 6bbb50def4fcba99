//! Out of bounds (the paper's `check_out_of_bounds` / `check_out_of_pitch`):
//! a ball wholly over a line (and not a goal) is put back in at the nearest
//! legal point inside; a robot whose torso is well outside the lines is reset
//! to its predetermined position.

use naosoccer_proto::{Event, RobotId};
use naosoccer_sim::Snapshot;

use super::{last_touch, Command, Field, KickOff, Outcome};

#[derive(Debug, Clone, Copy)]
pub struct OutOfBoundsRule {
    field: Field,
    ball_inset: f32,
    robot_margin: f32,
}

impl OutOfBoundsRule {
    pub fn new(field: Field, ball_inset: f32, robot_margin: f32) -> OutOfBoundsRule {
        OutOfBoundsRule {
            field,
            ball_inset,
            robot_margin,
        }
    }

    /// Where an out ball goes back in: the nearest point of the pitch shrunk
    /// by the inset. `None` while the ball is in play.
    pub fn ball_restart(&self, snap: &Snapshot) -> Option<(f32, f32)> {
        let f = &self.field;
        let [x, y, _] = snap.ball.pos;
        if f.contains(x, y, f.ball_radius) {
            return None;
        }
        let hx = (f.half_length - self.ball_inset).max(0.0);
        let hy = (f.half_width - self.ball_inset).max(0.0);
        Some((x.clamp(-hx, hx), y.clamp(-hy, hy)))
    }

    /// The ball: call only when no goal was scored this tick.
    pub fn check_ball(&self, snap: &Snapshot, tick: u64, out: &mut Outcome) -> bool {
        let Some((x, y)) = self.ball_restart(snap) else {
            return false;
        };
        let last = last_touch(snap).map(RobotId::team);
        out.events.push(Event::BallOut {
            tick,
            x,
            y,
            last_touch: last,
        });
        out.commands.push(Command::PlaceBall { x, y });
        true
    }

    /// The robots. `down[i]`: robot i lies fallen; a lying robot is left
    /// where it is until it has got up.
    pub fn check_robots(
        &self,
        snap: &Snapshot,
        down: &[bool],
        kickoff: &KickOff,
        tick: u64,
        out: &mut Outcome,
    ) {
        for (i, r) in snap.robots.iter().enumerate() {
            if down.get(i).copied().unwrap_or(false)
                || self.field.contains(r.pos[0], r.pos[1], self.robot_margin)
            {
                continue;
            }
            let Some(robot) = RobotId::from_index(i) else {
                continue;
            };
            let [x, y, heading] = kickoff.home(robot);
            out.events.push(Event::RobotOut { tick, robot });
            out.commands.push(Command::ResetRobot {
                robot,
                x,
                y,
                heading,
            });
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::RulesConfig;
    use crate::rules::testing::{field, snapshot};

    fn rule() -> OutOfBoundsRule {
        OutOfBoundsRule::new(field(), 0.2, 0.3)
    }

    #[test]
    fn ball_in_play_is_left_alone() {
        let mut s = snapshot();
        s.ball.pos = [2.9, 2.2, 0.05];
        assert_eq!(rule().ball_restart(&s), None);
    }

    #[test]
    fn ball_over_touch_line_goes_back_at_nearest_point_inside() {
        let mut s = snapshot();
        s.ball.pos = [1.0, 2.5, 0.05];
        assert_eq!(rule().ball_restart(&s), Some((1.0, 2.05)));
        s.ball.pos = [-3.4, -2.6, 0.05];
        assert_eq!(rule().ball_restart(&s), Some((-2.8, -2.05)));
    }

    #[test]
    fn robot_outside_is_reset_home_unless_lying() {
        let mut s = snapshot();
        s.robots[5].pos = [0.0, -2.9, 0.3];
        let kickoff = KickOff::new(&RulesConfig::default());
        let mut out = Outcome::default();
        let mut down = [false; 8];
        down[5] = true;
        rule().check_robots(&s, &down, &kickoff, 7, &mut out);
        assert!(out.events.is_empty());
        down[5] = false;
        rule().check_robots(&s, &down, &kickoff, 7, &mut out);
        let robot = RobotId::from_index(5).unwrap();
        assert_eq!(out.events, vec![Event::RobotOut { tick: 7, robot }]);
        let [x, y, heading] = kickoff.home(robot);
        assert_eq!(
            out.commands,
            vec![Command::ResetRobot {
                robot,
                x,
                y,
                heading
            }]
        );
    }
}
