//! One match played alone and watched tick by tick: the CLI's `match`
//! (recording, live view, Ctrl-C), `bench sim` and the end-to-end tests,
//! which compare it with the same match played on a server.

use std::ops::ControlFlow;
use std::time::Instant;

use naosoccer_policy::{PolicyError, PolicyKind};
use naosoccer_proto::{MatchStats, Score};
use naosoccer_referee::MatchConfig;

use super::{Batch, Fixture, Side, Ticked};

/// What a match played alone reports.
#[derive(Debug, Clone, PartialEq)]
pub struct MatchOutcome {
    pub seed: u64,
    /// Control ticks played.
    pub ticks: u64,
    /// Game time played, seconds.
    pub sim_seconds: f64,
    /// Wall-clock time the match took, seconds (the only wall-clock figure;
    /// nothing in the match depends on it).
    pub wall_seconds: f64,
    pub score: Score,
    pub stats: MatchStats,
    /// `Match::state_hash` at the end: equal for equal matches on one build.
    pub state_hash: u64,
    /// Referee events over the match.
    pub events: u64,
}

/// Plays the match of `fixture`, `first` against `second`, calling `watch`
/// after every control tick. It stops at the match's end (a scenario's:
/// its first end condition that holds), or after a tick for which `watch`
/// says `Break` (Ctrl-C): the outcome is then the match as far as it went
/// (`ticks` below the match's length).
pub fn play_one(
    cfg: &MatchConfig,
    first: &mut Side,
    second: &mut Side,
    fixture: Fixture<'_>,
    mut watch: impl FnMut(&Ticked<'_>) -> ControlFlow<()>,
) -> Result<MatchOutcome, PolicyError> {
    let mut batch = Batch::new(cfg, first, second, [fixture])?;
    let start = Instant::now();
    while !batch.is_over() {
        batch.step(1);
        if watch(&batch.ticked(0)).is_break() {
            break;
        }
    }
    let wall_seconds = start.elapsed().as_secs_f64();
    let p = batch.played(0);
    Ok(MatchOutcome {
        seed: p.seed,
        ticks: p.ticks,
        sim_seconds: p.sim_seconds,
        wall_seconds,
        score: p.score,
        stats: p.stats,
        state_hash: p.state_hash,
        events: p.events,
    })
}

/// A whole match of `cfg` with `seed` between two built-in teams, `blue`
/// against `red`, calling `on_tick` after every control tick.
pub fn play_match(
    cfg: &MatchConfig,
    seed: u64,
    blue: &PolicyKind,
    red: &PolicyKind,
    mut on_tick: impl FnMut(&Ticked<'_>),
) -> Result<MatchOutcome, PolicyError> {
    play_one(
        cfg,
        &mut Side::Builtin(*blue),
        &mut Side::Builtin(*red),
        Fixture::kick_off(seed),
        |t| {
            on_tick(t);
            ControlFlow::Continue(())
        },
    )
}

impl MatchOutcome {
    /// The `naosoccer match --json` object. `state_hash` is a string of 16
    /// lower-case hex digits: JSON numbers lose precision above 2^53 in many
    /// readers, a string does not.
    pub fn to_json(&self) -> serde_json::Value {
        let team = |t: &naosoccer_proto::TeamStats| {
            serde_json::json!({
                "goals": t.goals,
                "control_rate": t.control_rate,
                "passes": t.passes,
                "aimed_passes": t.aimed_passes,
                "shots": t.shots,
                "falls": t.falls,
                "out_of_bounds": t.out_of_bounds,
            })
        };
        serde_json::json!({
            "seed": self.seed,
            "ticks": self.ticks,
            "sim_seconds": self.sim_seconds,
            "wall_seconds": self.wall_seconds,
            "score": { "blue": self.score.blue, "red": self.score.red },
            "stats": { "blue": team(&self.stats.blue), "red": team(&self.stats.red) },
            "state_hash": format!("{:016x}", self.state_hash),
        })
    }
}
