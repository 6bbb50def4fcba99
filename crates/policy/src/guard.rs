//! The own-goal guard of the decision-level MDP
//! ([`crate::DecisionConfig::own_goal_guard`]): near its own goal, a robot
//! may not walk into the ball or kick it while facing that goal.
//!
//! Learned teams without it push the ball over their own goal line: a
//! robot comes to a ball lying at the line from the field side, facing its
//! goal, and walks into it (of six recorded matches of a 80M-transition
//! team against `scripted`, every own goal but one came that way; the
//! other was a fall onto the ball).

use naosoccer_proto::Observation;
use serde::{Deserialize, Serialize};

use crate::actions::{ActionSet, NetAction};

/// Where the guard holds, in the team's frame (own goal at x = -`half_length`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OwnGoalGuard {
    /// Half the field length (m): the own goal line is at x = -this.
    pub half_length: f32,
    /// Half the goal mouth (m).
    pub goal_half_width: f32,
    /// The guard holds while the ball is this close to the own goal line
    /// (m) and no further than 0.3 m outside the posts sideways.
    pub depth: f32,
}

impl OwnGoalGuard {
    /// The guard on a pitch of this field length and goal width: within
    /// 0.6 m of the goal line.
    pub fn for_pitch(field_length: f32, goal_width: f32) -> OwnGoalGuard {
        OwnGoalGuard {
            half_length: field_length / 2.0,
            goal_half_width: goal_width / 2.0,
            depth: 0.6,
        }
    }

    /// The actions (as bits, `1 << index`) the robot that received `obs`
    /// may not choose: `forward` and `shoot` while the ball lies within
    /// `depth` of the own goal line in front of the goal, at most 0.5 m
    /// ahead of the robot and at most 0.3 m to its side, and the robot
    /// faces its own goal line (its heading points toward -x by more than
    /// 0.2 of its length). Turning, `stay`, `pass` and the walking actions
    /// stay open.
    pub fn banned(&self, obs: &Observation) -> ActionSet {
        let me = obs.me();
        let ball = [obs.ball.x, obs.ball.y];
        let near_goal =
            ball[0] < -self.half_length + self.depth && ball[1].abs() < self.goal_half_width + 0.3;
        if me.fallen || !near_goal {
            return 0;
        }
        let (s, c) = me.heading.sin_cos();
        let d = [ball[0] - me.x, ball[1] - me.y];
        let ahead = d[0] * c + d[1] * s;
        let side = -d[0] * s + d[1] * c;
        if c < -0.2 && ahead > 0.0 && ahead < 0.5 && side.abs() < 0.3 {
            NetAction::Forward.bit() | NetAction::Shoot.bit()
        } else {
            0
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use naosoccer_proto::{BallObs, Player, RobotObs, Team, Tick, PLAYERS_PER_TEAM};

    fn obs(me: RobotObs, ball: [f32; 2]) -> Observation {
        let r = RobotObs {
            x: 0.0,
            y: 0.0,
            heading: 0.0,
            fallen: false,
            busy: false,
        };
        let mut own = [r; PLAYERS_PER_TEAM];
        own[1] = me;
        Observation {
            tick: Tick::ZERO,
            team: Team::Red,
            player: Player::new(1).unwrap(),
            time_left: 600.0,
            score: Default::default(),
            own,
            opponents: [r; PLAYERS_PER_TEAM],
            ball: BallObs {
                x: ball[0],
                y: ball[1],
                vx: 0.0,
                vy: 0.0,
            },
            control: [false; PLAYERS_PER_TEAM],
            opponent_control: false,
            reward: 0.0,
            half: 1,
            set_play: None,
        }
    }

    fn robot(x: f32, y: f32, heading: f32) -> RobotObs {
        RobotObs {
            x,
            y,
            heading,
            fallen: false,
            busy: false,
        }
    }

    #[test]
    fn facing_the_own_goal_at_a_ball_on_its_line_walking_and_kicking_are_banned() {
        let g = OwnGoalGuard::for_pitch(6.0, 2.6);
        let both = NetAction::Forward.bit() | NetAction::Shoot.bit();
        // A recorded case: the ball at the line, the robot 0.15 m from it,
        // facing its goal at an angle.
        let o = obs(robot(-2.82, -1.0, 2.4), [-2.92, -0.9]);
        assert_eq!(g.banned(&o), both);
        // Straight at the goal, the ball 0.3 m in front of it.
        assert_eq!(g.banned(&obs(robot(-2.4, 0.0, 3.1), [-2.7, 0.0])), both);
    }

    #[test]
    fn elsewhere_the_guard_bans_nothing() {
        let g = OwnGoalGuard::for_pitch(6.0, 2.6);
        // Facing the field, the ball at the line behind the robot's path.
        assert_eq!(g.banned(&obs(robot(-2.95, 0.0, 0.0), [-2.8, 0.0])), 0);
        // Facing the own goal but far from it.
        assert_eq!(g.banned(&obs(robot(0.3, 0.0, 3.1), [0.0, 0.0])), 0);
        // Near the goal line but wide of the posts.
        assert_eq!(g.banned(&obs(robot(-2.6, 2.0, 3.1), [-2.8, 2.0])), 0);
        // The ball near the goal but not in front of the robot.
        assert_eq!(g.banned(&obs(robot(-2.4, 0.6, 3.1), [-2.7, 0.0])), 0);
        // Lying robots decide nothing.
        let mut lying = robot(-2.4, 0.0, 3.1);
        lying.fallen = true;
        assert_eq!(g.banned(&obs(lying, [-2.7, 0.0])), 0);
    }
}
