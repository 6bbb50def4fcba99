//! Synthetic snapshots for the rules' unit tests: no physics involved.

use super::field::Field;
use naosoccer_sim::{BallState, RobotState, Snapshot};

pub fn field() -> Field {
    Field {
        half_length: 3.0,
        half_width: 2.25,
        goal_half_width: 1.3,
        crossbar: 0.8,
        ball_radius: 0.05,
    }
}

/// Ball at rest at the centre, robots upright in two rows far from it.
pub fn snapshot() -> Snapshot {
    let robot = |i: usize| {
        let blue = i < 4;
        let x = if blue { -1.5 } else { 1.5 };
        RobotState {
            pos: [x, (i % 4) as f32 - 1.5, 0.3],
            heading: if blue { 0.0 } else { std::f32::consts::PI },
            ..RobotState::default()
        }
    };
    Snapshot {
        step: 0,
        ball: BallState {
            pos: [0.0, 0.0, 0.05],
            vel: [0.0; 3],
        },
        robots: std::array::from_fn(robot),
        kicks: Vec::new(),
    }
}
