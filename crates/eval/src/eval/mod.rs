//! Evaluation: many whole matches between two teams, each a built-in policy
//! or a trained network, and the paper's Table I (average goals, ball-control
//! rate, average passes) plus shots and win/draw/loss, with 95% confidence
//! intervals over matches and a Wilson interval on the win rate.
//!
//! Optionally half the matches swap the sides, and each team is still
//! reported under its own name. Match seeds come from their own derivation
//! ([`eval_match_seed`]): they have the top bit set and training seeds
//! ([`episode_seed`]) have it clear, so an evaluation never replays a
//! match a training run saw.
//!
//! The matches are played by the crate's one runner ([`crate::run`]): side
//! by side, a trained team deciding for all its robots in all matches in
//! one forward pass a tick.
//!
//! An evaluation can be played in blocks (`--first-match`): match `i` has
//! the same seed and sides in a block as in the whole run, by its global
//! index. An [`EvalReport`] keeps every match's [`MatchRecord`], so reports
//! of blocks merge ([`EvalReport::merge`]) into the report of the whole run,
//! statistics and all, computed here and nowhere else.

use naosoccer_policy::PolicyError;
use naosoccer_proto::{MatchStats, PerTeam, Score, Team};
use naosoccer_referee::MatchConfig;
use serde::{Deserialize, Serialize};

use crate::run::{Batch, Fixture, Played};

mod report;
mod seeds;
mod stats;
mod table;
#[cfg(test)]
mod tests;

pub use report::{config_hash, EvalReport, ReportError};
pub use seeds::{episode_seed, eval_match_seed, legacy_episode_seed, SeedScheme, EVAL_SEED_BIT};
pub use stats::{summarise, t95, Estimate, Rate, Record, TeamSummary};
pub use table::format_table;

/// One side of an evaluation (the runner's).
pub use crate::run::Side;

/// How an evaluation is played: matches `first_match .. first_match +
/// matches` of the evaluation that `seed`, `both_sides` and `seeds` define.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct EvalPlan {
    pub matches: usize,
    /// The global index of the first match played (0 for a whole run).
    pub first_match: usize,
    pub seed: u64,
    /// Odd-numbered matches (by global index) swap the sides: the first
    /// team plays red.
    pub both_sides: bool,
    pub seeds: SeedScheme,
}

impl EvalPlan {
    /// Whether match `i` (a global index) has the first team playing red.
    pub fn swapped(&self, i: usize) -> bool {
        self.both_sides && i % 2 == 1
    }

    /// The seed of match `i` (a global index).
    pub fn match_seed(&self, i: usize) -> u64 {
        self.seeds.match_seed(self.seed, i)
    }

    /// The global indices of the matches played.
    pub fn indices(&self) -> std::ops::Range<usize> {
        self.first_match..self.first_match + self.matches
    }
}

/// One finished match.
#[derive(Debug, Clone, PartialEq)]
pub struct MatchResult {
    /// Its global index in the evaluation.
    pub index: usize,
    pub seed: u64,
    /// By colour.
    pub score: Score,
    pub stats: MatchStats,
    /// By colour: passes of at least [`LONG_PASS_METRES`].
    pub long_passes: PerTeam<u32>,
    pub state_hash: u64,
    /// The first team (`--blue`) played red.
    pub swapped: bool,
}

/// A pass this long or longer (m, from where the ball was kicked to where
/// the receiver took control) counts among the long passes. Most passes
/// the statistics count are kicks into a teammate standing at the ball,
/// under a metre (docs/LEARNING.md); a pass of a metre or more moves the
/// ball between players who stand apart.
pub const LONG_PASS_METRES: f32 = 1.0;

impl MatchResult {
    /// An evaluation's match as the runner played it.
    fn of(p: &Played) -> MatchResult {
        MatchResult {
            index: p.index,
            seed: p.seed,
            score: p.score,
            stats: p.stats,
            long_passes: p.long_passes,
            state_hash: p.state_hash,
            swapped: p.swapped,
        }
    }

    /// The colour the first team (`first`: true) or the second played.
    pub fn team_of(&self, first: bool) -> Team {
        if first != self.swapped {
            Team::Blue
        } else {
            Team::Red
        }
    }

    /// Goals of the first team (`first`: true) or the second.
    pub fn goals_of(&self, first: bool) -> u32 {
        *self.score.get(self.team_of(first))
    }

    /// What the summary needs of this match.
    pub fn record(&self) -> MatchRecord {
        let pair = |f: &dyn Fn(bool) -> u32| [f(true), f(false)];
        let team = |first: bool| self.stats.team(self.team_of(first));
        MatchRecord {
            index: self.index,
            seed: self.seed,
            swapped: self.swapped,
            goals: pair(&|first| self.goals_of(first)),
            control_rate_percent: [true, false].map(|first| 100.0 * team(first).control_rate),
            passes: pair(&|first| team(first).passes),
            aimed_passes: pair(&|first| team(first).aimed_passes),
            long_passes: pair(&|first| *self.long_passes.get(self.team_of(first))),
            shots: pair(&|first| team(first).shots),
            goals_open_play: pair(&|first| team(first).goals_open_play),
            goals_restart: pair(&|first| team(first).goals_restart),
            goals_own_goal: pair(&|first| team(first).goals_own_goal),
            goals_disallowed: pair(&|first| team(first).goals_disallowed),
            state_hash: self.state_hash,
        }
    }
}

/// One match of an evaluation as its report keeps it (`results` in
/// `eval --json`): every pair is (first team, second team), the first being
/// `--blue` whichever colour it played.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MatchRecord {
    /// The global index of the match in the evaluation.
    pub index: usize,
    pub seed: u64,
    /// The first team played red.
    pub swapped: bool,
    pub goals: [u32; 2],
    /// Each team's share of the ticks in which a team controlled the ball.
    pub control_rate_percent: [f64; 2],
    pub passes: [u32; 2],
    /// Passes whose kick was a `pass` swung toward a receiver (protocol
    /// 1.6's `aimed`; 0 in reports written before they were counted).
    #[serde(default)]
    pub aimed_passes: [u32; 2],
    /// Passes of at least [`LONG_PASS_METRES`] (0 in reports written
    /// before they were counted).
    #[serde(default)]
    pub long_passes: [u32; 2],
    pub shots: [u32; 2],
    /// Goals by phase (protocol 1.4's statistics; 0 in reports written
    /// before them): from open play, from the team's own restarts, and the
    /// other team's own goals; and goals that did not count.
    #[serde(default)]
    pub goals_open_play: [u32; 2],
    #[serde(default)]
    pub goals_restart: [u32; 2],
    #[serde(default)]
    pub goals_own_goal: [u32; 2],
    #[serde(default)]
    pub goals_disallowed: [u32; 2],
    /// The match's final state hash (the same on every machine of one build).
    pub state_hash: u64,
}
/// Plays the matches of `plan` between `first` and `second`, in index
/// order: match `i` (a global index) has seed `plan.match_seed(i)`, and
/// `first` plays blue unless `plan.swapped(i)`.
pub fn play_matches(
    cfg: &MatchConfig,
    first: &mut Side,
    second: &mut Side,
    plan: &EvalPlan,
    threads: usize,
) -> Result<Vec<MatchResult>, PolicyError> {
    let all = play_matches_until(cfg, first, second, plan, threads, &|| false)?;
    Ok(all.expect("never stopped"))
}

/// [`play_matches`], asking `stop` before every tick: once it says yes,
/// the matches are dropped unfinished and the answer is `None` (Ctrl-C).
pub fn play_matches_until(
    cfg: &MatchConfig,
    first: &mut Side,
    second: &mut Side,
    plan: &EvalPlan,
    threads: usize,
    stop: &dyn Fn() -> bool,
) -> Result<Option<Vec<MatchResult>>, PolicyError> {
    let fixtures = plan.indices().map(|i| Fixture {
        index: i,
        seed: plan.match_seed(i),
        swapped: plan.swapped(i),
        scenario: None,
    });
    let mut batch = Batch::new(cfg, first, second, fixtures)?;
    if !batch.play(threads, stop) {
        return Ok(None);
    }
    Ok(Some(batch.results().iter().map(MatchResult::of).collect()))
}
