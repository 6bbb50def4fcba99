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
//! The loop is the evaluation's (crate::eval): starts side by side, a
//! trained team deciding for all its robots in all starts in one forward
//! pass a tick, built-in robots stepped on threads; it differs in how a
//! start ends (its scenario's judge, not the match clock).

use std::collections::BTreeMap;

use naosoccer_policy::{Policy, PolicyError};
use naosoccer_proto::{Action, Event, Observation, RobotId, Team, PLAYERS_PER_TEAM, ROBOTS};
use naosoccer_referee::{Ending, Judge, Match, MatchConfig, Scenario};
use serde_json::{json, Value};

use crate::eval::{eval_match_seed, for_each_slot, Rate, Side};

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

struct Slot {
    m: Match,
    judge: Judge,
    obs: Vec<Observation>,
    policies: Vec<Option<Box<dyn Policy>>>,
    decided: [Action; ROBOTS],
    index: usize,
    ending: Option<Ending>,
    events: Vec<Event>,
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
    let mut slots = Vec::with_capacity(plan.starts);
    for i in 0..plan.starts {
        let colour = plan.own(i);
        let m = Match::with_scenario(cfg, plan.start_seed(i), scenario, colour)?;
        let seed = m.seed();
        let policies = RobotId::all()
            .map(|r| {
                let side = if r.team() == colour {
                    &*own
                } else {
                    &*opponent
                };
                match side {
                    Side::Builtin(k) => Some(k.build(seed, r)),
                    Side::Learned(_) => None,
                }
            })
            .collect();
        let mut slot = Slot {
            judge: scenario.judge(cfg, colour, m.tick()),
            obs: (0..ROBOTS)
                .map(|_| naosoccer_referee::blank_observation())
                .collect(),
            policies,
            decided: [Action::Stay; ROBOTS],
            index: i,
            ending: None,
            events: Vec::with_capacity(16),
            m,
        };
        observe_all(&mut slot);
        slots.push(slot);
    }
    while slots.iter().any(|s| s.ending.is_none()) {
        if stop() {
            return Ok(None);
        }
        for (is_own, side) in [(true, &mut *own), (false, &mut *opponent)] {
            let Side::Learned(policy) = side else {
                continue;
            };
            let live: Vec<usize> = (0..slots.len())
                .filter(|&i| slots[i].ending.is_none())
                .collect();
            let mut acts = vec![0usize; live.len() * PLAYERS_PER_TEAM];
            let teams: Vec<(u64, &[Observation])> = live
                .iter()
                .map(|&i| {
                    let base = team_of(&slots[i], is_own).index() * PLAYERS_PER_TEAM;
                    (
                        slots[i].m.seed(),
                        &slots[i].obs[base..base + PLAYERS_PER_TEAM],
                    )
                })
                .collect();
            policy.act_matches(&teams, &mut acts);
            for (j, &i) in live.iter().enumerate() {
                let base = team_of(&slots[i], is_own).index() * PLAYERS_PER_TEAM;
                for p in 0..PLAYERS_PER_TEAM {
                    let a = policy.action(acts[j * PLAYERS_PER_TEAM + p], &slots[i].obs[base + p]);
                    slots[i].decided[base + p] = a;
                }
            }
        }
        for_each_slot(&mut slots, threads, step_slot);
    }
    Ok(Some(
        slots
            .iter()
            .map(|s| StartResult {
                index: s.index,
                seed: s.m.seed(),
                own: s.judge.own(),
                ending: s.ending.expect("every start ended"),
                state_hash: s.m.state_hash(),
            })
            .collect(),
    ))
}

fn team_of(slot: &Slot, own: bool) -> Team {
    if own {
        slot.judge.own()
    } else {
        slot.judge.own().other()
    }
}

fn observe_all(slot: &mut Slot) {
    for r in RobotId::all() {
        slot.m
            .observe_into(r.team(), r.player(), &mut slot.obs[r.index()]);
    }
}

fn step_slot(slot: &mut Slot) {
    if slot.ending.is_some() {
        return;
    }
    for (i, p) in slot.policies.iter_mut().enumerate() {
        if let Some(p) = p {
            slot.decided[i] = p.act(&slot.obs[i]);
        }
    }
    // `step` lends its events out of the match; a copy into a reused
    // buffer lets the judge read the match and the events together.
    slot.events.clear();
    let events = slot.m.step(&slot.decided);
    slot.events.extend_from_slice(events);
    slot.ending = slot.judge.check(&slot.m, &slot.events);
    if slot.ending.is_none() {
        observe_all(slot);
    }
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
