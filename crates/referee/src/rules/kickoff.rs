//! Kick-off: predetermined places per player, ball on the centre spot. The
//! first half's kick-off goes to the team the configuration names, or to the
//! winner of a coin toss seeded by the match seed; the second half's to the
//! other team (SPL); after a goal the conceding team kicks off.

use naosoccer_proto::{RobotId, Team, PLAYERS_PER_TEAM};

use crate::config::{FirstKickOff, Placement, RulesConfig};

/// The kick-off formations, turned into world coordinates once.
#[derive(Debug, Clone)]
pub struct KickOff {
    attack: [Placement; PLAYERS_PER_TEAM],
    defend: [Placement; PLAYERS_PER_TEAM],
    first: Team,
}

impl KickOff {
    /// `first`: the team that kicks off the first half.
    pub fn new(rules: &RulesConfig, first: Team) -> KickOff {
        KickOff {
            attack: rules.kickoff_attack,
            defend: rules.kickoff_defend,
            first,
        }
    }

    /// The team that kicks off the first half under `rule` in the match
    /// seeded `seed`. The coin is a splitmix64 mix of the seed, so
    /// neighbouring seeds toss independently.
    pub fn first_team(rule: FirstKickOff, seed: u64) -> Team {
        match rule {
            FirstKickOff::Blue => Team::Blue,
            FirstKickOff::Red => Team::Red,
            FirstKickOff::Coin => {
                let mut z = seed ^ 0x6b69_636b_5f6f_6666; // "kick_off"
                z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
                z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
                z ^= z >> 31;
                if z & 1 == 0 {
                    Team::Blue
                } else {
                    Team::Red
                }
            }
        }
    }

    /// The team that kicks off the first half.
    pub fn first(&self) -> Team {
        self.first
    }

    /// The team that kicks off the second half.
    pub fn second(&self) -> Team {
        self.first.other()
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
        let k = KickOff::new(&RulesConfig::default(), Team::Blue);
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

    #[test]
    fn the_coin_is_fair_and_fixed_by_the_seed() {
        let blue = (0..1000u64)
            .filter(|&s| KickOff::first_team(FirstKickOff::Coin, s) == Team::Blue)
            .count();
        // Binomial(1000, 0.5): 3.5 sigma is about 55.
        assert!(
            (445..=555).contains(&blue),
            "blue won {blue} of 1000 tosses"
        );
        for s in 0..20 {
            assert_eq!(
                KickOff::first_team(FirstKickOff::Coin, s),
                KickOff::first_team(FirstKickOff::Coin, s)
            );
        }
        assert_eq!(KickOff::first_team(FirstKickOff::Red, 3), Team::Red);
        let k = KickOff::new(&RulesConfig::default(), Team::Red);
        assert_eq!((k.first(), k.second()), (Team::Red, Team::Blue));
    }
}
