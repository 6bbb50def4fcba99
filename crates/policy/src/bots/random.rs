//! A uniformly random one of the paper's five actions every tick (never
//! `pass`). Each robot has its own ChaCha stream seeded from the match seed
//! and its robot id, so a match is repeatable and robots do not mirror each
//! other.

use naosoccer_proto::{Action, Observation, RobotId};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::Policy;

#[derive(Debug, Clone)]
pub struct RandomPolicy {
    rng: ChaCha8Rng,
}

impl RandomPolicy {
    pub fn new(seed: u64, robot: RobotId) -> RandomPolicy {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        // One stream per robot, independent of the others.
        rng.set_stream(robot.index() as u64 + 1);
        RandomPolicy { rng }
    }
}

impl Policy for RandomPolicy {
    fn act(&mut self, _obs: &Observation) -> Action {
        Action::PAPER[self.rng.random_range(0..Action::PAPER.len())]
    }

    fn name(&self) -> &str {
        "random"
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use naosoccer_proto::Team;
    use naosoccer_proto::Tick;

    fn obs() -> Observation {
        Observation {
            tick: Tick::ZERO,
            team: Team::Blue,
            player: naosoccer_proto::Player::new(0).unwrap(),
            time_left: 0.0,
            score: Default::default(),
            own: Default::default(),
            opponents: Default::default(),
            ball: Default::default(),
            control: Default::default(),
            opponent_control: false,
            reward: 0.0,
            half: 1,
            set_play: None,
        }
    }

    fn run(seed: u64, robot: usize) -> Vec<Action> {
        let mut p = RandomPolicy::new(seed, RobotId::from_index(robot).unwrap());
        let o = obs();
        (0..50).map(|_| p.act(&o)).collect()
    }

    #[test]
    fn same_seed_and_robot_same_actions_otherwise_different() {
        assert_eq!(run(7, 3), run(7, 3));
        assert_ne!(run(7, 3), run(7, 4));
        assert_ne!(run(7, 3), run(8, 3));
        // Every action comes up.
        let a = run(1, 0);
        for act in Action::PAPER {
            assert!(a.contains(&act), "{act:?} never drawn");
        }
    }
}
