//! Out of bounds (the paper's `check_out_of_bounds` / `check_out_of_pitch`,
//! with SPL's restarts): a ball wholly over a line (and not a goal) restarts
//! with a set play for the team that did not touch it last:
//!
//! - over a touch line: a **kick-in**, the ball on the touch line where it
//!   left (`ball_inset` inside it);
//! - over a goal line, last touched by the attackers (or by nobody): a
//!   **goal kick** for the defenders, the ball on the front corner of their
//!   goal area on the side where it left;
//! - over a goal line, last touched by the defenders: a **corner kick** for
//!   the attackers, the ball in the corner on that side (`ball_inset` inside
//!   both lines).
//!
//! Which line a ball crossed near a corner: the one it is further past.
//! A kick-in after a ball that nobody has touched goes to the team whose
//! half it left from (its defenders). A robot whose torso is well outside
//! the lines, standing or lying, is reset upright to its predetermined
//! position.

use naosoccer_proto::{Event, RobotId, SetPlayKind, Team, Tick, ROBOTS};
use naosoccer_sim::Snapshot;

use super::field::{goal_kick_spot, last_touch, Field};
use super::kickoff::KickOff;
use super::outcome::{Command, Outcome};

/// A restart the rule awards.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Restart {
    pub kind: SetPlayKind,
    /// The team that takes it.
    pub team: Team,
    /// Where the ball goes, world frame.
    pub x: f32,
    pub y: f32,
}

#[derive(Debug, Clone, Copy)]
pub struct OutOfBoundsRule {
    field: Field,
    ball_inset: f32,
    robot_margin: f32,
    goal_area_depth: f32,
    goal_area_half_width: f32,
}

impl OutOfBoundsRule {
    pub fn new(
        field: Field,
        ball_inset: f32,
        robot_margin: f32,
        goal_area_depth: f32,
        goal_area_width: f32,
    ) -> OutOfBoundsRule {
        OutOfBoundsRule {
            field,
            ball_inset,
            robot_margin,
            goal_area_depth,
            goal_area_half_width: goal_area_width / 2.0,
        }
    }

    /// The set play an out ball restarts with; `None` while it is in play.
    /// `last` is the team that touched it last, if any.
    pub fn restart(&self, x: f32, y: f32, last: Option<Team>) -> Option<Restart> {
        let f = &self.field;
        if f.contains(x, y, f.ball_radius) {
            return None;
        }
        let over_goal_line = x.abs() - f.half_length > y.abs() - f.half_width;
        let side_y = if y < 0.0 { -1.0 } else { 1.0 };
        if !over_goal_line {
            // Kick-in for the team that did not touch it last.
            let team = match last {
                Some(t) => t.other(),
                // Nobody touched it: the defenders of the half it left from.
                None if x < 0.0 => Team::Blue,
                None => Team::Red,
            };
            let hx = f.half_length - self.ball_inset;
            return Some(Restart {
                kind: SetPlayKind::KickIn,
                team,
                x: x.clamp(-hx, hx),
                y: side_y * (f.half_width - self.ball_inset),
            });
        }
        // Over the goal line of the team defending that end: blue defends -x.
        let defenders = if x < 0.0 { Team::Blue } else { Team::Red };
        let side_x = if x < 0.0 { -1.0 } else { 1.0 };
        if last == Some(defenders) {
            Some(Restart {
                kind: SetPlayKind::CornerKick,
                team: defenders.other(),
                x: side_x * (f.half_length - self.ball_inset),
                y: side_y * (f.half_width - self.ball_inset),
            })
        } else {
            let (x, y) = goal_kick_spot(
                f,
                self.goal_area_depth,
                self.goal_area_half_width,
                defenders,
                y,
            );
            Some(Restart {
                kind: SetPlayKind::GoalKick,
                team: defenders,
                x,
                y,
            })
        }
    }

    /// The ball: call only when no goal was scored this tick. Emits
    /// `BallOut` and the set play's award, and asks for it.
    pub fn check_ball(&self, snap: &Snapshot, tick: Tick, out: &mut Outcome) -> Option<Restart> {
        let [x, y, _] = snap.ball.pos;
        let last = last_touch(snap).map(RobotId::team);
        let r = self.restart(x, y, last)?;
        out.events.push(Event::BallOut {
            tick,
            x: r.x,
            y: r.y,
            last_touch: last,
        });
        out.commands.push(Command::SetPlay {
            kind: r.kind,
            team: r.team,
            x: r.x,
            y: r.y,
        });
        Some(r)
    }

    /// The robots: one whose torso is further than the margin outside the
    /// lines goes back to its predetermined place, upright, whether it
    /// stands or lies. Robots out of play (`off`, a scenario's absent
    /// robots) are left where they are.
    pub fn check_robots(
        &self,
        snap: &Snapshot,
        kickoff: &KickOff,
        off: &[bool; ROBOTS],
        tick: Tick,
        out: &mut Outcome,
    ) {
        for (i, r) in snap.robots.iter().enumerate() {
            if off[i] || self.field.contains(r.pos[0], r.pos[1], self.robot_margin) {
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
        OutOfBoundsRule::new(field(), 0.05, 0.3, 0.6, 3.4)
    }

    #[test]
    fn ball_in_play_is_left_alone() {
        assert_eq!(rule().restart(2.9, 2.2, Some(Team::Blue)), None);
        // On the line is in.
        assert_eq!(rule().restart(1.0, 2.25 + 0.04, None), None);
    }

    #[test]
    fn touch_line_gives_a_kick_in_to_the_other_team_where_it_left() {
        let r = rule().restart(1.0, 2.4, Some(Team::Blue)).unwrap();
        assert_eq!(
            r,
            Restart {
                kind: SetPlayKind::KickIn,
                team: Team::Red,
                x: 1.0,
                y: 2.2
            }
        );
        let r = rule().restart(-2.99, -2.5, Some(Team::Red)).unwrap();
        assert_eq!(
            (r.kind, r.team, r.x, r.y),
            (SetPlayKind::KickIn, Team::Blue, -2.95, -2.2)
        );
        // Nobody touched it: the defenders of that half.
        assert_eq!(rule().restart(1.0, 2.4, None).unwrap().team, Team::Red);
        assert_eq!(rule().restart(-1.0, 2.4, None).unwrap().team, Team::Blue);
    }

    #[test]
    fn attackers_over_the_goal_line_give_a_goal_kick() {
        // Blue attacks +x; blue kicked it wide of red's goal.
        let r = rule().restart(3.2, -1.8, Some(Team::Blue)).unwrap();
        assert_eq!(
            r,
            Restart {
                kind: SetPlayKind::GoalKick,
                team: Team::Red,
                x: 2.4,
                y: -1.7
            }
        );
        let r = rule().restart(-3.2, 1.5, None).unwrap();
        assert_eq!(
            (r.kind, r.team, r.x, r.y),
            (SetPlayKind::GoalKick, Team::Blue, -2.4, 1.7)
        );
    }

    #[test]
    fn defenders_over_their_own_goal_line_give_a_corner_kick() {
        let r = rule().restart(3.2, 1.5, Some(Team::Red)).unwrap();
        assert_eq!(
            r,
            Restart {
                kind: SetPlayKind::CornerKick,
                team: Team::Blue,
                x: 2.95,
                y: 2.2
            }
        );
        let r = rule().restart(-3.1, -1.4, Some(Team::Blue)).unwrap();
        assert_eq!(
            (r.kind, r.team, r.x, r.y),
            (SetPlayKind::CornerKick, Team::Red, -2.95, -2.2)
        );
    }

    #[test]
    fn near_a_corner_the_line_it_is_further_past_decides() {
        // 0.3 past the goal line, 0.1 past the touch line: goal line.
        let r = rule().restart(3.3, 2.35, Some(Team::Blue)).unwrap();
        assert_eq!(r.kind, SetPlayKind::GoalKick);
        // 0.1 past the goal line, 0.3 past the touch line: touch line.
        let r = rule().restart(3.1, 2.55, Some(Team::Blue)).unwrap();
        assert_eq!(r.kind, SetPlayKind::KickIn);
    }

    #[test]
    fn check_ball_reports_and_asks_for_the_set_play() {
        let mut s = snapshot();
        s.ball.pos = [1.0, 2.5, 0.05];
        s.robots[2].last_ball_touch_step = Some(10);
        let mut out = Outcome::default();
        let r = rule().check_ball(&s, Tick::new(7), &mut out).unwrap();
        assert_eq!(r.team, Team::Red);
        assert_eq!(
            out.events,
            vec![Event::BallOut {
                tick: Tick::new(7),
                x: 1.0,
                y: 2.2,
                last_touch: Some(Team::Blue)
            }]
        );
        assert_eq!(
            out.commands,
            vec![Command::SetPlay {
                kind: SetPlayKind::KickIn,
                team: Team::Red,
                x: 1.0,
                y: 2.2
            }]
        );
    }

    #[test]
    fn robot_outside_is_reset_home_standing_or_lying() {
        let mut s = snapshot();
        s.robots[5].pos = [0.0, -2.9, 0.1];
        let kickoff = KickOff::new(&RulesConfig::default(), Team::Blue);
        let mut out = Outcome::default();
        rule().check_robots(&s, &kickoff, &[false; ROBOTS], Tick::new(7), &mut out);
        let robot = RobotId::from_index(5).unwrap();
        assert_eq!(
            out.events,
            vec![Event::RobotOut {
                tick: Tick::new(7),
                robot
            }]
        );
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
