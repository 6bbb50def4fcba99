//! Re-simulating a recording and comparing every tick's state.

use naosoccer_proto::Tick;
use naosoccer_referee::{Match, Scenario};

use crate::messages::StateRecord;
use crate::reader::Recording;
use crate::RecordError;

/// What a replay found.
#[derive(Debug, Clone, PartialEq)]
pub enum ReplayOutcome {
    /// Every recorded state was reproduced bit for bit (by state hash).
    Identical {
        /// Control ticks re-simulated.
        ticks: u64,
        /// Whether the recording was cut short (only its completed part was checked).
        truncated: bool,
    },
    /// The first tick whose re-simulated state differs from the recording.
    Diverged {
        tick: Tick,
        recorded: Box<StateRecord>,
        replayed: Box<StateRecord>,
    },
}

/// The recorded match as it started: from its configuration and seed, and
/// from its scenario when it started from one.
pub fn recorded_start(rec: &Recording) -> Result<Match, RecordError> {
    Ok(match &rec.meta.scenario {
        None => Match::new(&rec.meta.config, rec.meta.seed)?,
        Some(s) => {
            let scenario = Scenario::from_toml(&s.toml, Some(&s.name))?;
            Match::with_scenario(&rec.meta.config, rec.meta.seed, &scenario, s.own)?
        }
    })
}

/// Re-runs the match from its config, seed and recorded actions (and the
/// recorded state changes, each applied before the tick it preceded, after
/// that tick's state was checked) and compares the state after every tick
/// with the recorded one.
pub fn replay(rec: &Recording) -> Result<ReplayOutcome, RecordError> {
    let mut m = recorded_start(rec)?;
    let mut states = rec.states.iter().peekable();
    let check = |m: &Match, recorded: &StateRecord| -> Option<ReplayOutcome> {
        // The hash covers the raw bits of every body and the referee's
        // state; the other fields are there to show a person what differs.
        let replayed = StateRecord::of(m);
        (replayed.state_hash != recorded.state_hash).then(|| ReplayOutcome::Diverged {
            tick: m.tick(),
            recorded: Box::new(recorded.clone()),
            replayed: Box::new(replayed),
        })
    };
    // States are written at the start (tick 0, or a scenario's first
    // tick) and after each step, in tick order.
    if let Some(s) = states.next_if(|s| s.tick == m.tick()) {
        if let Some(d) = check(&m, s) {
            return Ok(d);
        }
    }
    let mut set_states = rec.set_states.iter().peekable();
    let mut ticks = 0;
    for a in &rec.actions {
        if a.tick != m.tick() {
            return Err(RecordError::NotARecording(format!(
                "actions for tick {} follow tick {}: ticks are missing",
                a.tick,
                m.tick()
            )));
        }
        if m.is_finished() {
            break;
        }
        // Changes recorded for an earlier tick cannot be re-applied where
        // they were made: the recording does not hold together.
        if let Some(s) = set_states.next_if(|s| s.tick < m.tick()) {
            return Err(RecordError::NotARecording(format!(
                "a state change for tick {} comes after tick {}",
                s.tick,
                m.tick()
            )));
        }
        while let Some(s) = set_states.next_if(|s| s.tick == m.tick()) {
            m.set_state(&s.change()).map_err(|e| {
                RecordError::NotARecording(format!(
                    "the state change recorded at tick {} is refused: {e}",
                    s.tick
                ))
            })?;
        }
        m.step(&a.actions);
        ticks += 1;
        while let Some(s) = states.next_if(|s| s.tick <= m.tick()) {
            if s.tick == m.tick() {
                if let Some(d) = check(&m, s) {
                    return Ok(d);
                }
            }
        }
    }
    Ok(ReplayOutcome::Identical {
        ticks,
        truncated: !rec.is_complete(),
    })
}
