//! The per-match observer seam: whoever wants to see a match tick by tick
//! (the MCAP recorder, benchmarks) implements [`MatchObserver`]; the server
//! asks [`Hooks::observer`] for one when it creates a match and calls it
//! from the match task, in tick order.

use naosoccer_proto::msg::{MatchEnd, MatchInfo};
use naosoccer_proto::{Action, Event, StateChange, Tick, ROBOTS};
use naosoccer_referee::Match;
use std::sync::Arc;
use std::time::Duration;

/// One played tick, as the match task saw it.
#[derive(Clone, Copy)]
pub struct TickRecord<'a> {
    /// The match after the tick (its `tick()` is one past the played tick).
    pub game: &'a Match,
    /// The tick that was played.
    pub tick: Tick,
    /// The actions applied, robot index order (misses already turned into `stay`).
    pub actions: &'a [Action; ROBOTS],
    pub events: &'a [Event],
    /// Real-time mode: how long after its scheduled instant the tick started.
    pub lateness: Option<Duration>,
}

/// Sees one match. Runs on the match task, so it must be quick (or hand the
/// data to its own task).
pub trait MatchObserver: Send {
    /// Before the first tick, with the match at kick-off.
    fn on_start(&mut self, info: &MatchInfo, game: &Match);
    fn on_tick(&mut self, record: &TickRecord<'_>);
    /// An admin set the state (`set_state`) before tick `tick` was played;
    /// `game` is the match after the change. Changes made while the match
    /// waited for its players come right after [`MatchObserver::on_start`].
    fn on_state_set(&mut self, tick: Tick, change: &StateChange, game: &Match) {
        let _ = (tick, change, game);
    }
    /// After the last tick (or at shutdown).
    fn on_end(&mut self, end: &MatchEnd, game: &Match);
}

/// Makes an observer for each new match, or `None` to leave it unobserved.
pub type ObserverFactory = dyn Fn(&MatchInfo) -> Option<Box<dyn MatchObserver>> + Send + Sync;

/// Makes the policy that plays robot `RobotId`'s slot, if nobody joins it,
/// in a match of the given seed.
pub type FillFactory =
    dyn Fn(u64, naosoccer_proto::RobotId) -> Box<dyn naosoccer_policy::Policy> + Send + Sync;

/// A team that plays the slots nobody joined, in every match, instead of
/// the match's `fill` (`naosoccer server --fill ppo:DIR`: a trained team).
#[derive(Clone)]
pub struct FillTeam {
    /// What the matches report as their `fill_team` and recordings name
    /// (`ppo:DIR`).
    pub spec: String,
    pub make: Arc<FillFactory>,
}

/// Extension points of a server.
#[derive(Clone, Default)]
pub struct Hooks {
    pub observer: Option<Arc<ObserverFactory>>,
    pub fill: Option<FillTeam>,
}

impl std::fmt::Debug for Hooks {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Hooks")
            .field("observer", &self.observer.is_some())
            .field("fill", &self.fill.as_ref().map(|t| &t.spec))
            .finish()
    }
}
