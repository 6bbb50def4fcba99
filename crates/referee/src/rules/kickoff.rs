//! Kick-off: predetermined places per player, ball on the centre spot. Blue
//! kicks off first; after a goal the conceding team does.

use naosoccer_proto::{RobotId, Team, PLAYERS_PER_TEAM};

use crate::config::{Placement, RulesConfig};

/// The kick-off formations, turned into world coordinates once.
#[derive(Debug, Clone)]
pub struct KickOff {
    attack: [Placement; PLAYERS_PER_TEAM],
    defend: [Placement; PLAYERS_PER_TEAM],
}

impl KickOff {
    /// The team that kicks off the match.
    pub const FIRST: Team = Team::Blue;

    pub fn new(rules: &RulesConfig) -> KickOff {
        KickOff {
            attack: rules.kickoff_attack,
            defend: rules.kickoff_defend,
        }
    }

    /// Where `robot` stands, world frame, when `kicking` kicks off.
    pub fn place(&self, robot: RobotId, kicking: Team) -> Placement {
        let table = if robot.team() == kicking {
            &self.attack
        } else {
            &self.defend
        };
        to_world(robot.team(), table[robot.player()])
    }

    /// The robot's predetermined position, world frame: where a robot that
    /// left the field is reset to.
    pub fn home(&self, robot: RobotId) -> Placement {
        to_world(robot.team(), self.defend[robot.player()])
    }
}

/// Team frame (own goal at -x) to world frame (blue's own goal at -x).
pub fn to_world(team: Team, [x, y, h]: Placement) -> Placement {
    match team {
        Team::Blue => [x, y, super::wrap_angle(h)],
        Team::Red => [-x, -y, super::wrap_angle(h + std::f32::consts::PI)],
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f32::consts::PI;

    #[test]
    fn red_places_are_blue_places_turned_half_round() {
        let k = KickOff::new(&RulesConfig::default());
        let b = k.place(RobotId::new(Team::Blue, 1).unwrap(), Team::Blue);
        let r = k.place(RobotId::new(Team::Red, 1).unwrap(), Team::Red);
        assert_eq!([-b[0], -b[1]], [r[0], r[1]]);
        assert!((r[2] - PI).abs() < 1e-6);
        // Everybody starts in its own half.
        for robot in RobotId::all() {
            for kicking in Team::BOTH {
                let [x, _, _] = k.place(robot, kicking);
                assert!(x * robot.team().direction() <= 0.0, "{robot:?} at {x}");
            }
        }
    }
}
