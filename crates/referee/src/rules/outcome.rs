//! What a tick of the rules produces: the [`Command`]s for the driver and
//! the [`Outcome`] that carries them with the tick's events.

use naosoccer_proto::{Event, RobotId, SetPlayKind, Team};

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
