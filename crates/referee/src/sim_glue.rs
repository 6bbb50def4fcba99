//! Where the referee reads the sim's configuration: kept in one place so a
//! renamed sim field touches one file.

use naosoccer_sim::SimConfig;

use crate::rules::Field;

pub(crate) fn field(cfg: &SimConfig) -> Field {
    Field {
        half_length: cfg.field_length / 2.0,
        half_width: cfg.field_width / 2.0,
        goal_half_width: cfg.goal_width / 2.0,
        crossbar: cfg.goal_height,
        ball_radius: cfg.ball_radius,
    }
}

/// Physics steps in one control tick (at least one).
pub(crate) fn steps_per_tick(cfg: &SimConfig, control_hz: f32) -> u32 {
    ((1.0 / (f64::from(control_hz) * f64::from(cfg.dt))).round() as u32).max(1)
}

#[cfg(test)]
pub(crate) fn synthetic_snapshot() -> naosoccer_sim::Snapshot {
    use naosoccer_sim::{BallState, RobotState, Snapshot};
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
