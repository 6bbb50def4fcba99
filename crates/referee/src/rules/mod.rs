//! The rules, one type per file. Each is a function of a sim
//! [`Snapshot`](naosoccer_sim::Snapshot) and
//! the control tick (plus the little memory the rule itself keeps, held in its
//! own type) that pushes [`Event`](naosoccer_proto::Event)s and [`Command`]s
//! into an [`Outcome`]. Their shared types live in [`outcome`] and [`field`],
//! which import no rule, so no two modules here import each other.
//! Rules never touch the sim: [`crate::Match`] applies the commands.

pub mod clock;
pub mod fall;
pub mod field;
pub mod goal;
pub mod kickoff;
pub mod out_of_bounds;
pub mod outcome;
pub mod pass;
pub mod possession;
pub mod restart;
pub mod set_play;
#[cfg(test)]
pub(crate) mod testing;

pub use clock::Clock;
pub use fall::FallRule;
pub use field::{last_touch, segment_distance, wrap_angle, Field};
pub use goal::GoalRule;
pub use kickoff::KickOff;
pub use out_of_bounds::OutOfBoundsRule;
pub use out_of_bounds::Restart;
pub use outcome::{Command, Outcome};
pub use pass::{PassMade, PassRule};
pub use possession::PossessionRule;
pub use restart::RestartRule;
pub use set_play::{ActiveSetPlay, SetPlayRule};
