//! Drills: many starts of one scenario between the team under test and the
//! scenario's opponents, each played until an end condition or its time
//! limit, and the success rate with its Wilson 95% interval; the academy is
//! every drill of a directory, one row each.
//!
//! Start `i` of a drill has the seed of evaluation match `i`
//! ([`eval_match_seed`]) and the team under test plays blue in the even
//! starts and red in the odd ones: `eval --scenario FILE --matches N` and
//! `academy --starts N` play the same starts of a drill.
//!
//! The starts are played by the crate's one runner ([`crate::run`]), as an
//! evaluation's matches are: side by side, a trained team deciding for all
//! its robots in all starts in one forward pass a tick, built-in robots
//! stepped on threads; a start ends at its scenario's first end condition
//! that holds (its judge), not with the match clock.

use std::collections::BTreeMap;

use naosoccer_policy::PolicyError;
use naosoccer_proto::Team;
use naosoccer_referee::{Ending, MatchConfig, Scenario};
use serde_json::{json, Value};

use crate::eval::{eval_match_seed, Rate, Side};
use crate::run::{Batch, Fixture};

/// Which starts of a drill are played: starts `0..starts` under `seed`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct DrillPlan {
    pub starts: usize,
    pub seed: u64,
}

impl DrillPlan {
    /// The seed of start `i`.
    pub fn start_seed(&self, i: usize) -> u64 {
        eval_match_seed(self.seed, i)
    }

    /// The colour the team under test plays in start `i`.
    pub fn own(&self, i: usize) -> Team {
        if i % 2 == 0 {
            Team::Blue
        } else {
            Team::Red
        }
    }
}

/// One finished start.
#[derive(Debug, Clone, PartialEq)]
pub struct StartResult {
    pub index: usize,
    pub seed: u64,
    pub own: Team,
    pub ending: Ending,
    /// `Match::state_hash` when it ended.
    pub state_hash: u64,
}

/// Plays the starts of `plan` of `scenario`: `own` is the team under test,
/// `opponent` the other side. `stop` is asked before every tick; once it
/// says yes the starts are dropped and the answer is `None` (Ctrl-C).
pub fn play_drill(
    cfg: &MatchConfig,
    scenario: &Scenario,
    own: &mut Side,
    opponent: &mut Side,
    plan: &DrillPlan,
    threads: usize,
    stop: &dyn Fn() -> bool,
) -> Result<Option<Vec<StartResult>>, PolicyError> {
    // The team under test is the runner's first side, and its colour the
    // scenario's own team's.
    let fixtures = (0..plan.starts).map(|i| Fixture {
        index: i,
        seed: plan.start_seed(i),
        swapped: plan.own(i) == Team::Red,
        scenario: Some((scenario, plan.own(i))),
    });
    let mut batch = Batch::new(cfg, own, opponent, fixtures)?;
    if !batch.play(threads, stop) {
        return Ok(None);
    }
    Ok(Some(
        batch
            .results()
            .iter()
            .map(|p| StartResult {
                index: p.index,
                seed: p.seed,
                own: plan.own(p.index),
                ending: p.ending.expect("every start ended"),
                state_hash: p.state_hash,
            })
            .collect(),
    ))
}

/// A drill's results: the academy table's row.
#[derive(Debug, Clone, PartialEq)]
pub struct DrillReport {
    pub drill: String,
    pub rate: Rate,
    /// Starts ended by each end condition (by name), and how many of those
    /// were successes.
    pub outcomes: BTreeMap<&'static str, (usize, usize)>,
    /// Game seconds from the start to the end of a successful start
    /// (`None` without one).
    pub mean_success_seconds: Option<f64>,
    /// Control ticks played over all starts.
    pub ticks: u64,
    /// The team under test and the opponents (team specs).
    pub policy: String,
    pub opponent: String,
}

impl DrillReport {
    pub fn new(
        drill: &str,
        policy: &str,
        opponent: &str,
        cfg: &MatchConfig,
        results: &[StartResult],
    ) -> DrillReport {
        let successes: Vec<&StartResult> = results.iter().filter(|r| r.ending.success).collect();
        let mut outcomes: BTreeMap<&'static str, (usize, usize)> = BTreeMap::new();
        for r in results {
            let e = outcomes.entry(r.ending.kind.name()).or_default();
            e.0 += 1;
            e.1 += usize::from(r.ending.success);
        }
        let hz = f64::from(cfg.control_hz);
        let mean_success_seconds = (!successes.is_empty()).then(|| {
            successes.iter().map(|r| r.ending.ticks as f64).sum::<f64>()
                / successes.len() as f64
                / hz
        });
        DrillReport {
            drill: drill.to_owned(),
            rate: Rate::wilson(successes.len(), results.len()),
            outcomes,
            mean_success_seconds,
            ticks: results.iter().map(|r| r.ending.ticks).sum(),
            policy: policy.to_owned(),
            opponent: opponent.to_owned(),
        }
    }

    /// The drill's object in `academy --json` (and `eval --scenario --json`).
    pub fn to_json(&self) -> Value {
        let outcomes: serde_json::Map<String, Value> = self
            .outcomes
            .iter()
            .map(|(k, &(n, ok))| ((*k).to_owned(), json!({"starts": n, "successes": ok})))
            .collect();
        json!({
            "drill": self.drill,
            "opponent": self.opponent,
            "starts": self.rate.n,
            "successes": self.rate.successes,
            "success_rate": self.rate.rate,
            "ci": [self.rate.low, self.rate.high],
            "mean_time_to_success": self.mean_success_seconds,
            "outcomes": outcomes,
            "ticks": self.ticks,
        })
    }
}

/// The academy table: one row per drill.
pub fn format_table(policy: &str, starts: usize, seed: u64, rows: &[DrillReport]) -> String {
    use std::fmt::Write;
    let mut s = String::new();
    let _ = writeln!(
        s,
        "academy: {policy}, {starts} starts a drill (seed {seed}; even starts as blue, odd as red)"
    );
    let w = rows.iter().map(|r| r.drill.len()).max().unwrap_or(5).max(5);
    let _ = writeln!(
        s,
        "{:<w$}  {:>22}  {:>9}  {:<10}  outcomes",
        "drill", "success % [95% CI]", "time (s)", "opponent"
    );
    for r in rows {
        let time = r
            .mean_success_seconds
            .map_or_else(|| "-".to_owned(), |t| format!("{t:.1}"));
        let outcomes: Vec<String> = r
            .outcomes
            .iter()
            .map(|(k, (n, _))| format!("{k} {n}"))
            .collect();
        let _ = writeln!(
            s,
            "{:<w$}  {:>22}  {:>9}  {:<10}  {}",
            r.drill,
            r.rate.to_string(),
            time,
            r.opponent,
            outcomes.join(", ")
        );
    }
    s
}

/// The academy's `--json` object.
pub fn to_json(policy: &str, starts: usize, seed: u64, rows: &[DrillReport], wall: f64) -> Value {
    let ticks: u64 = rows.iter().map(|r| r.ticks).sum();
    json!({
        "policy": policy,
        "starts": starts,
        "seed": seed,
        "drills": rows.iter().map(DrillReport::to_json).collect::<Vec<_>>(),
        "ticks": ticks,
        "wall_seconds": wall,
    })
}
