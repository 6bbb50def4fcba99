//! The rules, one type per file. Each is a function of a sim [`Snapshot`] and
//! the control tick (plus the little memory the rule itself keeps, held in its
//! own type) that pushes [`Event`]s and [`Command`]s into an [`Outcome`].
//! Rules never touch the sim: [`crate::Match`] applies the commands.

use naosoccer_proto::{Event, RobotId, SetPlayKind, Team};
use naosoccer_sim::{SimConfig, Snapshot};

pub mod clock;
pub mod fall;
pub mod goal;
pub mod kickoff;
pub mod out_of_bounds;
pub mod pass;
pub mod possession;
pub mod set_play;

pub use clock::Clock;
pub use fall::FallRule;
pub use goal::GoalRule;
pub use kickoff::KickOff;
pub use out_of_bounds::OutOfBoundsRule;
pub use out_of_bounds::Restart;
pub use pass::{PassMade, PassRule};
pub use possession::PossessionRule;
pub use set_play::{ActiveSetPlay, SetPlayRule};

/// What a rule asks the driver to do to the world.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Command {
    /// Put the ball at rest at (x, y), world frame, for a set play that
    /// `team` takes (kick-in, goal kick or corner kick).
    SetPlay {
        kind: SetPlayKind,
        team: Team,
        x: f32,
        y: f32,
    },
    /// Put a robot upright and at rest at (x, y) with a heading, world frame.
    ResetRobot {
        robot: RobotId,
        x: f32,
        y: f32,
        heading: f32,
    },
    /// Stand a fallen robot up where it lies.
    StandUp { robot: RobotId },
    /// Ball to the centre spot and every robot to its kick-off place; `team` kicks off.
    KickOff { team: Team },
}

/// A tick's events and commands, in the order the rules produced them.
/// The driver keeps one and clears it every tick, so the hot loop does not
/// allocate once the vectors have grown.
#[derive(Debug, Default)]
pub struct Outcome {
    pub events: Vec<Event>,
    pub commands: Vec<Command>,
}

impl Outcome {
    pub fn clear(&mut self) {
        self.events.clear();
        self.commands.clear();
    }
}

/// The pitch as the rules see it, in world coordinates (centre spot at the
/// origin, blue's own goal at -x).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Field {
    /// Half the length between the goal lines (metres).
    pub half_length: f32,
    /// Half the width between the touch lines.
    pub half_width: f32,
    /// Half the goal mouth, inner edge of a post to the centre.
    pub goal_half_width: f32,
    /// Height of the crossbar's underside.
    pub crossbar: f32,
    pub ball_radius: f32,
}

impl Field {
    /// The pitch as the sim builds it.
    pub fn from_sim(cfg: &SimConfig) -> Field {
        Field {
            half_length: cfg.field_length / 2.0,
            half_width: cfg.field_width / 2.0,
            goal_half_width: cfg.goal_width / 2.0,
            crossbar: cfg.goal_height,
            ball_radius: cfg.ball_radius,
        }
    }

    /// Whether a point is on the pitch (lines included).
    pub fn contains(&self, x: f32, y: f32, margin: f32) -> bool {
        x.abs() <= self.half_length + margin && y.abs() <= self.half_width + margin
    }
}

/// Angle wrapped to (-pi, pi].
pub fn wrap_angle(a: f32) -> f32 {
    use std::f32::consts::{PI, TAU};
    let mut a = a % TAU;
    if a > PI {
        a -= TAU;
    } else if a <= -PI {
        a += TAU;
    }
    a
}

/// The robot that touched the ball last, by the sim's contact record.
pub fn last_touch(snap: &Snapshot) -> Option<RobotId> {
    let mut best: Option<(u64, usize)> = None;
    for (i, r) in snap.robots.iter().enumerate() {
        if let Some(step) = r.last_ball_touch_step {
            // Later touch wins; on the same step the lower index, for a fixed order.
            if best.is_none_or(|(s, _)| step > s) {
                best = Some((step, i));
            }
        }
    }
    best.and_then(|(_, i)| RobotId::from_index(i))
}

#[cfg(test)]
pub(crate) mod testing {
    //! Synthetic snapshots for the rules' unit tests: no physics involved.
    use super::Field;
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
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f32::consts::PI;

    #[test]
    fn wrap_angle_lands_in_half_open_interval() {
        assert!((wrap_angle(PI) - PI).abs() < 1e-6);
        assert!((wrap_angle(-PI) - PI).abs() < 1e-6);
        assert!((wrap_angle(3.0 * PI / 2.0) + PI / 2.0).abs() < 1e-5);
        assert!((wrap_angle(-5.0 * PI / 2.0) + PI / 2.0).abs() < 1e-5);
        assert_eq!(wrap_angle(0.25), 0.25);
    }
}
