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
//! Matches run side by side; a trained team decides for all its robots in all
//! matches in one forward pass per tick.
//!
//! An evaluation can be played in blocks (`--first-match`): match `i` has
//! the same seed and sides in a block as in the whole run, by its global
//! index. An [`EvalReport`] keeps every match's [`MatchRecord`], so reports
//! of blocks merge ([`EvalReport::merge`]) into the report of the whole run,
//! statistics and all, computed here and nowhere else.

use naosoccer_policy::{LearnedPolicy, Policy, PolicyError, PolicyKind};
use naosoccer_proto::{
    Action, Event, MatchStats, Observation, PerTeam, RobotId, Score, Team, PLAYERS_PER_TEAM, ROBOTS,
};
use naosoccer_referee::{Match, MatchConfig};
use serde::{Deserialize, Serialize};
use serde_json::{json, Value};

/// One side of an evaluation.
pub enum Side {
    Builtin(PolicyKind),
    Learned(Box<LearnedPolicy>),
}

impl Side {
    /// `scripted` | `scripted:KEY=VAL,...` | `scripted:FILE.toml` | `random`
    /// | `idle` | `ppo:DIR` | `dqn:DIR` (and the other trained-team specs).
    pub fn parse(spec: &str) -> Result<Side, PolicyError> {
        if !naosoccer_policy::is_builtin_spec(spec) {
            return Ok(Side::Learned(Box::new(LearnedPolicy::load(spec)?)));
        }
        spec.parse::<PolicyKind>()
            .map(Side::Builtin)
            .map_err(|e| PolicyError::Spec {
                spec: spec.to_string(),
                reason: format!("{e}; or ppo:DIR, dqn:DIR"),
            })
    }
}

/// How evaluation matches get their seeds.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum SeedScheme {
    /// [`eval_match_seed`]: never a training match's seed.
    #[default]
    Eval,
    /// [`legacy_episode_seed`]`(seed, i, 0)`, the seed of training match
    /// `i`'s first episode before the two were separated: it replays
    /// evaluations made then.
    Legacy,
}

impl SeedScheme {
    pub fn name(self) -> &'static str {
        match self {
            SeedScheme::Eval => "eval",
            SeedScheme::Legacy => "legacy",
        }
    }

    pub fn match_seed(self, seed: u64, index: usize) -> u64 {
        match self {
            SeedScheme::Eval => eval_match_seed(seed, index),
            SeedScheme::Legacy => legacy_episode_seed(seed, index, 0),
        }
    }
}

/// The bit that tells evaluation seeds (set) from training seeds
/// (`env::episode_seed`, clear).
pub const EVAL_SEED_BIT: u64 = 1 << 63;

/// The seed of evaluation match `index` under `--seed seed`: a splitmix64
/// mix of its own (another stream constant than training's), with the top
/// bit set. Training seeds have it clear, so an evaluation never plays a
/// match any training run played, whatever the two `--seed`s.
pub fn eval_match_seed(seed: u64, index: usize) -> u64 {
    let mut z = (seed ^ 0x5EED_E7A1_0000_0000).wrapping_add(
        (index as u64)
            .wrapping_add(1)
            .wrapping_mul(0x9E37_79B9_7F4A_7C15),
    );
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    (z ^ (z >> 31)) | EVAL_SEED_BIT
}

/// The seed of training match `index`'s `episode`-th episode: a splitmix64
/// mix, so neighbouring matches and episodes get unrelated streams. Its top
/// bit is always clear: evaluation seeds ([`eval_match_seed`]) have it set,
/// so no evaluation replays a training match.
pub fn episode_seed(seed: u64, index: usize, episode: u64) -> u64 {
    legacy_episode_seed(seed, index, episode) & !EVAL_SEED_BIT
}

/// [`episode_seed`] before training and evaluation seeds were separated:
/// evaluations made then replay with it (`eval --legacy-seeds`).
pub fn legacy_episode_seed(seed: u64, index: usize, episode: u64) -> u64 {
    let mut z = seed
        ^ (index as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15)
        ^ episode.wrapping_mul(0xD1B5_4A32_D192_ED03);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

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

struct Slot {
    m: Match,
    obs: Vec<Observation>,
    policies: Vec<Option<Box<dyn Policy>>>,
    decided: [Action; ROBOTS],
    /// By colour, so far.
    long_passes: PerTeam<u32>,
    swapped: bool,
    index: usize,
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
    let mut slots = Vec::with_capacity(plan.matches);
    for i in plan.indices() {
        let m = Match::new(cfg, plan.match_seed(i))?;
        let s = m.seed();
        let swapped = plan.swapped(i);
        let policies = RobotId::all()
            .map(|r| {
                let side = if (r.team() == Team::Blue) != swapped {
                    &*first
                } else {
                    &*second
                };
                match side {
                    Side::Builtin(k) => Some(k.build(s, r)),
                    Side::Learned(_) => None,
                }
            })
            .collect();
        let mut slot = Slot {
            obs: (0..ROBOTS)
                .map(|_| naosoccer_referee::blank_observation())
                .collect(),
            policies,
            decided: [Action::Stay; ROBOTS],
            long_passes: PerTeam::default(),
            swapped,
            index: i,
            m,
        };
        observe_all(&mut slot);
        slots.push(slot);
    }
    let mut acts = Vec::new();
    while slots.iter().any(|s| !s.m.is_finished()) {
        if stop() {
            return Ok(None);
        }
        for (is_first, side) in [(true, &mut *first), (false, &mut *second)] {
            let Side::Learned(policy) = side else {
                continue;
            };
            let live: Vec<usize> = (0..slots.len())
                .filter(|&i| !slots[i].m.is_finished())
                .collect();
            let n = live.len() * PLAYERS_PER_TEAM;
            acts.resize(n, 0usize);
            // Each match's team as one policy playing that match would see
            // it: draws keyed by (match seed, team, player, tick), and the
            // decision-level MDP's per-robot holds kept by the policy.
            let teams: Vec<(u64, &[Observation])> = live
                .iter()
                .map(|&i| {
                    let base = team_of(&slots[i], is_first).index() * PLAYERS_PER_TEAM;
                    (
                        slots[i].m.seed(),
                        &slots[i].obs[base..base + PLAYERS_PER_TEAM],
                    )
                })
                .collect();
            policy.act_matches(&teams, &mut acts);
            for (j, &i) in live.iter().enumerate() {
                let team = team_of(&slots[i], is_first);
                let base = team.index() * PLAYERS_PER_TEAM;
                for p in 0..PLAYERS_PER_TEAM {
                    let a = policy.action(acts[j * PLAYERS_PER_TEAM + p], &slots[i].obs[base + p]);
                    slots[i].decided[team.index() * PLAYERS_PER_TEAM + p] = a;
                }
            }
        }
        for_each_slot(&mut slots, threads, step_slot);
    }
    Ok(Some(
        slots
            .iter()
            .map(|s| MatchResult {
                index: s.index,
                seed: s.m.seed(),
                score: s.m.score(),
                stats: s.m.stats(),
                long_passes: s.long_passes,
                state_hash: s.m.state_hash(),
                swapped: s.swapped,
            })
            .collect(),
    ))
}

fn team_of(slot: &Slot, first: bool) -> Team {
    if first != slot.swapped {
        Team::Blue
    } else {
        Team::Red
    }
}

fn observe_all(slot: &mut Slot) {
    for r in RobotId::all() {
        slot.m
            .observe_into(r.team(), r.player(), &mut slot.obs[r.index()]);
    }
}

/// Runs `step` on every slot, the slots split into up to `threads` runs
/// of neighbours on scoped threads. Each slot holds its own match, so the
/// thread count changes no result. Evaluations and the academy step their
/// batches with it.
pub(crate) fn for_each_slot<S: Send>(slots: &mut [S], threads: usize, step: fn(&mut S)) {
    let threads = threads.clamp(1, slots.len().max(1));
    let per = slots.len().div_ceil(threads).max(1);
    if threads == 1 {
        slots.iter_mut().for_each(step);
    } else {
        std::thread::scope(|s| {
            for chunk in slots.chunks_mut(per) {
                s.spawn(move || chunk.iter_mut().for_each(step));
            }
        });
    }
}

fn step_slot(slot: &mut Slot) {
    if slot.m.is_finished() {
        return;
    }
    for (i, p) in slot.policies.iter_mut().enumerate() {
        if let Some(p) = p {
            slot.decided[i] = p.act(&slot.obs[i]);
        }
    }
    for e in slot.m.step(&slot.decided) {
        if let Event::Pass { from, distance, .. } = *e {
            if distance >= LONG_PASS_METRES {
                *slot.long_passes.get_mut(from.team()) += 1;
            }
        }
    }
    observe_all(slot);
}

/// A mean with its 95% confidence interval (Student's t over the samples).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Estimate {
    pub mean: f64,
    /// Half-width of the 95% interval.
    pub ci95: f64,
    pub n: usize,
}

/// Two-sided 95% Student t quantiles for 1..=30 degrees of freedom.
const T95: [f64; 30] = [
    12.706, 4.303, 3.182, 2.776, 2.571, 2.447, 2.365, 2.306, 2.262, 2.228, 2.201, 2.179, 2.160,
    2.145, 2.131, 2.120, 2.110, 2.101, 2.093, 2.086, 2.080, 2.074, 2.069, 2.064, 2.060, 2.056,
    2.052, 2.048, 2.045, 2.042,
];

/// The two-sided 95% t quantile for `df` degrees of freedom.
pub fn t95(df: usize) -> f64 {
    match df {
        0 => f64::NAN,
        d if d <= 30 => T95[d - 1],
        d if d <= 60 => 2.000 + (2.042 - 2.000) * (60 - d) as f64 / 30.0,
        d if d <= 120 => 1.980 + (2.000 - 1.980) * (120 - d) as f64 / 60.0,
        _ => 1.96,
    }
}

impl Estimate {
    pub fn of(xs: &[f64]) -> Estimate {
        let n = xs.len();
        if n == 0 {
            return Estimate {
                mean: f64::NAN,
                ci95: f64::NAN,
                n,
            };
        }
        let mean = xs.iter().sum::<f64>() / n as f64;
        if n == 1 {
            return Estimate {
                mean,
                ci95: f64::NAN,
                n,
            };
        }
        let var = xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1) as f64;
        Estimate {
            mean,
            ci95: t95(n - 1) * (var / n as f64).sqrt(),
            n,
        }
    }
}

impl std::fmt::Display for Estimate {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let p = f.precision().unwrap_or(2);
        if self.ci95.is_nan() {
            write!(f, "{:.p$}", self.mean)
        } else {
            write!(f, "{:.p$} ± {:.p$}", self.mean, self.ci95)
        }
    }
}

/// A proportion with its Wilson score 95% interval.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Rate {
    pub successes: usize,
    pub n: usize,
    pub rate: f64,
    pub low: f64,
    pub high: f64,
}

impl Rate {
    /// `successes` of `n`, with the Wilson interval at z = 1.96: unlike the
    /// normal approximation it stays inside [0, 1] and is not empty at 0 or
    /// `n` successes.
    pub fn wilson(successes: usize, n: usize) -> Rate {
        if n == 0 {
            return Rate {
                successes,
                n,
                rate: f64::NAN,
                low: f64::NAN,
                high: f64::NAN,
            };
        }
        let z = 1.96f64;
        let nf = n as f64;
        let p = successes as f64 / nf;
        let denom = 1.0 + z * z / nf;
        let centre = (p + z * z / (2.0 * nf)) / denom;
        let half = z * (p * (1.0 - p) / nf + z * z / (4.0 * nf * nf)).sqrt() / denom;
        Rate {
            successes,
            n,
            rate: p,
            // The interval holds p; at 0 or n successes rounding could put
            // the bound a hair inside it.
            low: (centre - half).clamp(0.0, p),
            high: (centre + half).clamp(p, 1.0),
        }
    }
}

impl std::fmt::Display for Rate {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{:.1} [{:.1}, {:.1}]",
            100.0 * self.rate,
            100.0 * self.low,
            100.0 * self.high
        )
    }
}

/// Wins, draws and losses.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Record {
    pub wins: usize,
    pub draws: usize,
    pub losses: usize,
}

impl Record {
    pub fn matches(&self) -> usize {
        self.wins + self.draws + self.losses
    }
}

/// One team's row of the table.
#[derive(Debug, Clone, PartialEq)]
pub struct TeamSummary {
    pub name: String,
    pub goals: Estimate,
    /// In percent.
    pub control_rate: Estimate,
    pub passes: Estimate,
    /// Passes of at least [`LONG_PASS_METRES`].
    pub long_passes: Estimate,
    pub shots: Estimate,
    /// Goals by phase, a match: from open play, from its own restarts, the
    /// other team's own goals, and its goals that did not count.
    pub goals_open_play: Estimate,
    pub goals_restart: Estimate,
    pub goals_own_goal: Estimate,
    pub goals_disallowed: Estimate,
    /// The other team's open-play goals, a match.
    pub goals_open_play_against: Estimate,
    pub wins: usize,
    pub draws: usize,
    pub losses: usize,
    /// Wins over all matches (a draw is not a win), Wilson 95%.
    pub win_rate: Rate,
    /// The matches it played as blue and as red.
    pub as_blue: Record,
    pub as_red: Record,
}

/// Table I over a set of matches, for the first team (`--blue`) and the
/// second, each under its own name whichever colour it played. The float
/// sums run in the order of `records`.
pub fn summarise(records: &[MatchRecord], first_name: &str, second_name: &str) -> [TeamSummary; 2] {
    [(0, first_name), (1, second_name)].map(|(k, name)| {
        let col = |f: &dyn Fn(&MatchRecord) -> f64| {
            Estimate::of(&records.iter().map(f).collect::<Vec<_>>())
        };
        let (mut as_blue, mut as_red) = (Record::default(), Record::default());
        for r in records {
            // The first team (k = 0) plays blue unless the match is swapped.
            let rec = if (k == 0) != r.swapped {
                &mut as_blue
            } else {
                &mut as_red
            };
            match r.goals[k].cmp(&r.goals[1 - k]) {
                std::cmp::Ordering::Greater => rec.wins += 1,
                std::cmp::Ordering::Equal => rec.draws += 1,
                std::cmp::Ordering::Less => rec.losses += 1,
            }
        }
        let wins = as_blue.wins + as_red.wins;
        TeamSummary {
            name: name.to_string(),
            goals: col(&|r| f64::from(r.goals[k])),
            control_rate: col(&|r| r.control_rate_percent[k]),
            passes: col(&|r| f64::from(r.passes[k])),
            long_passes: col(&|r| f64::from(r.long_passes[k])),
            shots: col(&|r| f64::from(r.shots[k])),
            goals_open_play: col(&|r| f64::from(r.goals_open_play[k])),
            goals_restart: col(&|r| f64::from(r.goals_restart[k])),
            goals_own_goal: col(&|r| f64::from(r.goals_own_goal[k])),
            goals_disallowed: col(&|r| f64::from(r.goals_disallowed[k])),
            goals_open_play_against: col(&|r| f64::from(r.goals_open_play[1 - k])),
            wins,
            draws: as_blue.draws + as_red.draws,
            losses: as_blue.losses + as_red.losses,
            win_rate: Rate::wilson(wins, records.len()),
            as_blue,
            as_red,
        }
    })
}

/// The table as text, one row per team, for `matches` matches from global
/// index `first_match` on.
pub fn format_table(rows: &[TeamSummary], matches: usize, first_match: usize) -> String {
    let both = rows
        .iter()
        .any(|r| r.as_red.matches() > 0 && r.as_blue.matches() > 0);
    let mut s = format!(
        "{matches} matches{}{}, mean ± 95% CI; win % with its Wilson 95% interval\n\
         {:<28} {:>14} {:>18} {:>16} {:>16} {:>16} {:>11} {:>20} {:>22} {:>15}\n",
        if first_match > 0 {
            format!(
                " (numbers {first_match} to {} of the evaluation)",
                first_match + matches - 1
            )
        } else {
            String::new()
        },
        if both {
            ", half with the sides swapped"
        } else {
            ""
        },
        "team",
        "average goals",
        "ball control %",
        "average passes",
        "passes >= 1 m",
        "average shots",
        "W/D/L",
        "win %",
        "open-play goals for/ag",
        "restart goals"
    );
    for r in rows {
        s.push_str(&format!(
            "{:<28} {:>14} {:>18} {:>16} {:>16} {:>16} {:>11} {:>20} {:>22} {:>15}\n",
            r.name,
            format!("{:.2}", r.goals),
            format!("{:.1}", r.control_rate),
            format!("{:.2}", r.passes),
            format!("{:.2}", r.long_passes),
            format!("{:.2}", r.shots),
            format!("{}/{}/{}", r.wins, r.draws, r.losses),
            r.win_rate.to_string(),
            format!(
                "{:.2} / {:.2}",
                r.goals_open_play.mean, r.goals_open_play_against.mean
            ),
            format!("{:.2}", r.goals_restart.mean),
        ));
    }
    if both {
        for r in rows {
            s.push_str(&format!(
                "{}: as blue {}/{}/{}, as red {}/{}/{}\n",
                r.name,
                r.as_blue.wins,
                r.as_blue.draws,
                r.as_blue.losses,
                r.as_red.wins,
                r.as_red.draws,
                r.as_red.losses
            ));
        }
    }
    s
}

/// A 64-bit FNV-1a hash of the match configuration's JSON form: reports
/// with the same hash were played under the same configuration.
pub fn config_hash(cfg: &MatchConfig) -> u64 {
    // Plain data (numbers, arrays, enums): serialising cannot fail.
    let text = serde_json::to_vec(cfg).expect("a match configuration serialises");
    text.iter().fold(0xcbf2_9ce4_8422_2325, |h, &b| {
        (h ^ u64::from(b)).wrapping_mul(0x0000_0100_0000_01b3)
    })
}

/// An evaluation's report: what `naosoccer eval --json` prints, and what
/// `eval --merge` reads back and merges. The statistics are always computed
/// from the per-match records, so a merged report is the report of one run
/// over the same matches.
#[derive(Debug, Clone, PartialEq)]
pub struct EvalReport {
    /// The first team's spec (`--blue`), then the second's (`--red`).
    pub names: [String; 2],
    pub plan: EvalPlan,
    /// The match length (the configuration's, after `--minutes`).
    pub minutes: f32,
    /// [`config_hash`] of the match configuration.
    pub config_hash: u64,
    /// One per match of `plan`, in index order.
    pub records: Vec<MatchRecord>,
    /// Wall-clock seconds the matches took to play (for a merged report,
    /// the sum of its parts').
    pub wall_seconds: f64,
}

/// Why a report could not be read or merged.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ReportError {
    /// Not the JSON of an `eval --json` with per-match results, or one
    /// whose records do not fit its own plan.
    #[error("{label}: {reason}")]
    Format { label: String, reason: String },
    /// Two reports of different evaluations.
    #[error(
        "{label} is not the evaluation of {first}: {field} is {found} there, {expected} in {first}"
    )]
    Mismatch {
        first: String,
        label: String,
        field: &'static str,
        expected: String,
        found: String,
    },
    /// A match is in two reports.
    #[error("match {index} is in both {first} and {second}")]
    Overlap {
        index: usize,
        first: String,
        second: String,
    },
    /// Matches between two reports are in none.
    #[error("{} (between {before} and {after})", missing(*.from, *.to))]
    Gap {
        from: usize,
        to: usize,
        before: String,
        after: String,
    },
    #[error("no reports to merge")]
    Empty,
}

fn missing(from: usize, to: usize) -> String {
    if from == to {
        format!("match {from} is missing")
    } else {
        format!("matches {from} to {to} are missing")
    }
}

/// The fields of an `eval --json` object that a report is rebuilt from
/// (the summaries are recomputed from `results`).
#[derive(Deserialize)]
struct ReportFile {
    matches: usize,
    first_match: usize,
    seed: u64,
    minutes: f32,
    both_sides: bool,
    seed_scheme: String,
    config_hash: String,
    blue: NamedTeam,
    red: NamedTeam,
    results: Vec<MatchRecord>,
    wall_seconds: f64,
}

#[derive(Deserialize)]
struct NamedTeam {
    name: String,
}

impl EvalReport {
    /// The report of `results`, played by `play_matches` under `plan` and `cfg`.
    pub fn new(
        names: [String; 2],
        plan: EvalPlan,
        cfg: &MatchConfig,
        results: &[MatchResult],
        wall_seconds: f64,
    ) -> EvalReport {
        EvalReport {
            names,
            plan,
            minutes: cfg.minutes,
            config_hash: config_hash(cfg),
            records: results.iter().map(MatchResult::record).collect(),
            wall_seconds,
        }
    }

    /// Each team's row: the first team's, then the second's.
    pub fn summary(&self) -> [TeamSummary; 2] {
        summarise(&self.records, &self.names[0], &self.names[1])
    }

    /// The `eval --json` object.
    pub fn to_json(&self) -> Value {
        let rows = self.summary();
        let est = |e: &Estimate| json!({"mean": e.mean, "ci95": e.ci95});
        let rate = |r: &Rate| json!({"rate": r.rate, "low": r.low, "high": r.high});
        let rec = |r: &Record| json!({"wins": r.wins, "draws": r.draws, "losses": r.losses});
        let team = |r: &TeamSummary| {
            json!({
                "name": r.name, "goals": est(&r.goals), "control_rate_percent": est(&r.control_rate),
                "passes": est(&r.passes), "long_passes": est(&r.long_passes), "shots": est(&r.shots),
                "goals_open_play": est(&r.goals_open_play), "goals_restart": est(&r.goals_restart),
                "goals_own_goal": est(&r.goals_own_goal), "goals_disallowed": est(&r.goals_disallowed),
                "goals_open_play_against": est(&r.goals_open_play_against),
                "wins": r.wins, "draws": r.draws, "losses": r.losses,
                "win_rate": rate(&r.win_rate), "as_blue": rec(&r.as_blue), "as_red": rec(&r.as_red),
            })
        };
        // Per match, the --blue team's goals first, whichever colour it played.
        let scores: Vec<_> = self.records.iter().map(|r| r.goals).collect();
        let swapped: Vec<_> = self.records.iter().map(|r| r.swapped).collect();
        json!({
            "matches": self.plan.matches, "first_match": self.plan.first_match,
            "seed": self.plan.seed, "minutes": self.minutes,
            "both_sides": self.plan.both_sides, "seed_scheme": self.plan.seeds.name(),
            "config_hash": format!("{:016x}", self.config_hash),
            "blue": team(&rows[0]), "red": team(&rows[1]), "scores": scores,
            "swapped": swapped, "results": self.records, "wall_seconds": self.wall_seconds,
        })
    }

    /// The table `naosoccer eval` prints.
    pub fn table(&self) -> String {
        format!(
            "{}({:.1} min matches, {:.1} s)\n",
            format_table(&self.summary(), self.plan.matches, self.plan.first_match),
            self.minutes,
            self.wall_seconds
        )
    }

    /// Reads back what [`to_json`](Self::to_json) wrote; `label` names the
    /// source in errors. Refuses objects without per-match `results` (from
    /// a naosoccer before them) and records that do not fit the plan.
    pub fn from_json(label: &str, v: &Value) -> Result<EvalReport, ReportError> {
        let bad = |reason: String| ReportError::Format {
            label: label.to_string(),
            reason,
        };
        if v.get("results").is_none() {
            return Err(bad(
                "no per-match \"results\": not the output of `naosoccer eval --json`, \
                 or of one older than --merge (play it again)"
                    .into(),
            ));
        }
        let f: ReportFile = serde_json::from_value(v.clone())
            .map_err(|e| bad(format!("not an `eval --json` object: {e}")))?;
        let seeds = match f.seed_scheme.as_str() {
            "eval" => SeedScheme::Eval,
            "legacy" => SeedScheme::Legacy,
            other => return Err(bad(format!("unknown seed_scheme {other:?}"))),
        };
        let config_hash = u64::from_str_radix(&f.config_hash, 16).map_err(|_| {
            bad(format!(
                "config_hash {:?} is not hexadecimal",
                f.config_hash
            ))
        })?;
        let plan = EvalPlan {
            matches: f.matches,
            first_match: f.first_match,
            seed: f.seed,
            both_sides: f.both_sides,
            seeds,
        };
        if f.matches == 0 || f.first_match.checked_add(f.matches).is_none() {
            return Err(bad(format!(
                "{} matches from match {}",
                f.matches, f.first_match
            )));
        }
        if f.results.len() != f.matches {
            return Err(bad(format!(
                "{} results for {} matches",
                f.results.len(),
                f.matches
            )));
        }
        for (i, r) in plan.indices().zip(&f.results) {
            if r.index != i || r.seed != plan.match_seed(i) || r.swapped != plan.swapped(i) {
                return Err(bad(format!(
                    "results[{}] (match {}, seed {}, swapped {}) is not match {i} of the plan \
                     (seed {}, swapped {})",
                    i - plan.first_match,
                    r.index,
                    r.seed,
                    r.swapped,
                    plan.match_seed(i),
                    plan.swapped(i)
                )));
            }
        }
        Ok(EvalReport {
            names: [f.blue.name, f.red.name],
            plan,
            minutes: f.minutes,
            config_hash,
            records: f.results,
            wall_seconds: f.wall_seconds,
        })
    }

    /// Merges reports of blocks of one evaluation (each with its label, for
    /// errors) into the report one run over all their matches gives. They
    /// must agree on the teams, seed, seed scheme, sides, match length and
    /// configuration, and their matches must form one run without gaps or
    /// overlaps. `wall_seconds` is the sum of theirs.
    pub fn merge(parts: &[(String, EvalReport)]) -> Result<EvalReport, ReportError> {
        let (first_label, first) = parts.first().ok_or(ReportError::Empty)?;
        for (label, r) in &parts[1..] {
            let checks: [(&'static str, String, String); 7] = [
                ("--blue", first.names[0].clone(), r.names[0].clone()),
                ("--red", first.names[1].clone(), r.names[1].clone()),
                ("seed", first.plan.seed.to_string(), r.plan.seed.to_string()),
                (
                    "seed_scheme",
                    first.plan.seeds.name().into(),
                    r.plan.seeds.name().into(),
                ),
                (
                    "both_sides",
                    first.plan.both_sides.to_string(),
                    r.plan.both_sides.to_string(),
                ),
                ("minutes", first.minutes.to_string(), r.minutes.to_string()),
                (
                    "config_hash",
                    format!("{:016x}", first.config_hash),
                    format!("{:016x}", r.config_hash),
                ),
            ];
            for (field, expected, found) in checks {
                if expected != found {
                    return Err(ReportError::Mismatch {
                        first: first_label.clone(),
                        label: label.clone(),
                        field,
                        expected,
                        found,
                    });
                }
            }
        }
        let mut order: Vec<&(String, EvalReport)> = parts.iter().collect();
        order.sort_by_key(|(_, r)| r.plan.first_match);
        for pair in order.windows(2) {
            let ((before, a), (after, b)) = (pair[0], pair[1]);
            let end = a.plan.indices().end;
            if b.plan.first_match < end {
                return Err(ReportError::Overlap {
                    index: b.plan.first_match,
                    first: before.clone(),
                    second: after.clone(),
                });
            }
            if b.plan.first_match > end {
                return Err(ReportError::Gap {
                    from: end,
                    to: b.plan.first_match - 1,
                    before: before.clone(),
                    after: after.clone(),
                });
            }
        }
        let records: Vec<MatchRecord> = order
            .iter()
            .flat_map(|(_, r)| r.records.iter().cloned())
            .collect();
        Ok(EvalReport {
            names: first.names.clone(),
            plan: EvalPlan {
                matches: records.len(),
                first_match: order[0].1.plan.first_match,
                ..first.plan
            },
            minutes: first.minutes,
            config_hash: first.config_hash,
            records,
            wall_seconds: order.iter().map(|(_, r)| r.wall_seconds).sum(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wilson_interval_matches_hand_computed_values() {
        // Values from the closed form, z = 1.96.
        for (k, n, low, high) in [
            (0, 10, 0.0, 0.277_540),
            (5, 10, 0.236_590, 0.763_410),
            (8, 10, 0.490_157, 0.943_319),
            (100, 100, 0.963_005, 1.0),
            (80, 100, 0.711_169, 0.866_634),
        ] {
            let r = Rate::wilson(k, n);
            assert!(
                (r.low - low).abs() < 1e-5 && (r.high - high).abs() < 1e-5,
                "{k}/{n}: {r:?}"
            );
            assert!(r.low <= r.rate && r.rate <= r.high);
        }
        assert!(Rate::wilson(0, 0).rate.is_nan());
        assert_eq!(Rate::wilson(8, 10).to_string(), "80.0 [49.0, 94.3]");
    }

    #[test]
    fn evaluation_seeds_never_meet_training_seeds() {
        let mut eval = std::collections::BTreeSet::new();
        for seed in 0..8 {
            for i in 0..200 {
                let s = eval_match_seed(seed, i);
                assert_ne!(s & EVAL_SEED_BIT, 0);
                eval.insert(s);
                for episode in 0..4 {
                    assert_eq!(episode_seed(seed, i, episode) & EVAL_SEED_BIT, 0);
                }
            }
        }
        // Distinct across seeds and matches.
        assert_eq!(eval.len(), 8 * 200);
        // The legacy scheme is the old training derivation, top bit and all.
        assert_eq!(
            SeedScheme::Legacy.match_seed(7, 3),
            legacy_episode_seed(7, 3, 0)
        );
        assert_eq!(
            episode_seed(7, 3, 0),
            legacy_episode_seed(7, 3, 0) & !EVAL_SEED_BIT
        );
    }

    fn short_config() -> MatchConfig {
        MatchConfig {
            minutes: 0.25,
            ..MatchConfig::default()
        }
    }

    #[test]
    fn both_sides_swaps_every_other_match_and_keeps_each_team_under_its_name() {
        let cfg = short_config();
        let plan = EvalPlan {
            matches: 4,
            first_match: 0,
            seed: 3,
            both_sides: true,
            seeds: SeedScheme::Eval,
        };
        let scripted = || Side::Builtin(PolicyKind::Scripted);
        let random = || Side::Builtin(PolicyKind::Random);
        let both = play_matches(&cfg, &mut scripted(), &mut random(), &plan, 1).unwrap();
        assert_eq!(
            both.iter().map(|r| r.swapped).collect::<Vec<_>>(),
            [false, true, false, true]
        );
        // A swapped match is the match with the teams named the other way
        // round: same seed, same play, bit for bit.
        let plain = EvalPlan {
            both_sides: false,
            ..plan
        };
        let reversed = play_matches(&cfg, &mut random(), &mut scripted(), &plain, 1).unwrap();
        let straight = play_matches(&cfg, &mut scripted(), &mut random(), &plain, 1).unwrap();
        for i in 0..4 {
            let expect = if i % 2 == 1 {
                &reversed[i]
            } else {
                &straight[i]
            };
            assert_eq!(both[i].seed, expect.seed);
            assert_eq!(both[i].score, expect.score);
            assert_eq!(both[i].state_hash, expect.state_hash);
        }
        let records: Vec<_> = both.iter().map(MatchResult::record).collect();
        let [first, second] = summarise(&records, "scripted", "random");
        assert_eq!(
            (first.name.as_str(), second.name.as_str()),
            ("scripted", "random")
        );
        assert_eq!(first.as_blue.matches(), 2);
        assert_eq!(first.as_red.matches(), 2);
        let goals: u32 = both.iter().map(|r| r.goals_of(true)).sum();
        let by_colour: u32 = (0..4)
            .map(|i| {
                if i % 2 == 1 {
                    reversed[i].score.red
                } else {
                    straight[i].score.blue
                }
            })
            .sum();
        assert_eq!(goals, by_colour);
        assert!((first.goals.mean - f64::from(goals) / 4.0).abs() < 1e-12);
        assert_eq!(first.wins, second.losses);
        assert_eq!(first.win_rate, Rate::wilson(first.wins, 4));
    }

    /// Long passes are the `pass` events of at least `LONG_PASS_METRES`,
    /// by the passer's team, recounted here from a replay of each match;
    /// scripted teams make both kinds, so a count of all passes or of none
    /// fails.
    #[test]
    fn long_passes_count_the_pass_events_of_a_metre_or_more() {
        let cfg = MatchConfig {
            minutes: 5.0,
            ..MatchConfig::default()
        };
        let plan = EvalPlan {
            matches: 2,
            first_match: 0,
            seed: 5,
            both_sides: true,
            seeds: SeedScheme::Eval,
        };
        let scripted = || Side::Builtin(PolicyKind::Scripted);
        let results = play_matches(&cfg, &mut scripted(), &mut scripted(), &plan, 1).unwrap();
        let (mut long, mut short) = (0, 0);
        for r in &results {
            let mut m = Match::new(&cfg, r.seed).unwrap();
            let mut policies: Vec<_> = RobotId::all()
                .map(|id| PolicyKind::Scripted.build(m.seed(), id))
                .collect();
            let mut obs = naosoccer_referee::blank_observation();
            let mut actions = [Action::Stay; ROBOTS];
            let mut by_colour = PerTeam::<u32>::default();
            while !m.is_finished() {
                for id in RobotId::all() {
                    m.observe_into(id.team(), id.player(), &mut obs);
                    actions[id.index()] = policies[id.index()].act(&obs);
                }
                for e in m.step(&actions) {
                    if let Event::Pass { from, distance, .. } = *e {
                        if distance >= LONG_PASS_METRES {
                            *by_colour.get_mut(from.team()) += 1;
                            long += 1;
                        } else {
                            short += 1;
                        }
                    }
                }
            }
            assert_eq!(m.state_hash(), r.state_hash, "the replay is the match");
            assert_eq!(r.long_passes, by_colour);
            let rec = r.record();
            for first in [true, false] {
                let k = usize::from(!first);
                assert_eq!(rec.long_passes[k], *by_colour.get(r.team_of(first)));
                assert!(rec.long_passes[k] <= rec.passes[k]);
            }
        }
        assert!(long > 0 && short > 0, "long {long}, short {short}");
        let records: Vec<_> = results.iter().map(MatchResult::record).collect();
        let [first, second] = summarise(&records, "a", "b");
        let total = first.long_passes.mean * 2.0 + second.long_passes.mean * 2.0;
        assert!((total - f64::from(long)).abs() < 1e-9);
        // Reports written before long passes were counted still read.
        let mut old = serde_json::to_value(&records[0]).unwrap();
        old.as_object_mut().unwrap().remove("long_passes");
        let back: MatchRecord = serde_json::from_value(old).unwrap();
        assert_eq!(back.long_passes, [0, 0]);
    }

    /// A block of an evaluation plays its matches as the whole run does, by
    /// global index; the reports of blocks merge into the whole run's,
    /// through their JSON; mismatched and incomplete sets are refused.
    #[test]
    fn blocks_play_the_whole_runs_matches_and_merge_into_its_report() {
        let cfg = short_config();
        let names = ["scripted".to_string(), "random".to_string()];
        let whole = EvalPlan {
            matches: 5,
            first_match: 0,
            seed: 9,
            both_sides: true,
            seeds: SeedScheme::Eval,
        };
        let play = |plan: EvalPlan| {
            let mut a = Side::Builtin(PolicyKind::Scripted);
            let mut b = Side::Builtin(PolicyKind::Random);
            let results = play_matches(&cfg, &mut a, &mut b, &plan, 2).unwrap();
            // Through the JSON, as --merge reads it.
            let json = EvalReport::new(names.clone(), plan, &cfg, &results, 1.0).to_json();
            EvalReport::from_json("part", &json).unwrap()
        };
        let full = play(whole);
        let block = |first_match, matches| {
            play(EvalPlan {
                first_match,
                matches,
                ..whole
            })
        };
        let (a, b, c) = (block(0, 2), block(2, 2), block(4, 1));
        assert_eq!(b.records[..], full.records[2..4]);
        assert_eq!(b.records[1].index, 3);
        assert!(b.records[1].swapped);
        let label = |s: &str, r: &EvalReport| (s.to_string(), r.clone());
        let merged = EvalReport::merge(&[label("c", &c), label("a", &a), label("b", &b)]).unwrap();
        assert_eq!(merged.wall_seconds, 3.0);
        assert_eq!(
            EvalReport {
                wall_seconds: 1.0,
                ..merged.clone()
            },
            full
        );
        assert_eq!(merged.to_json()["blue"], full.to_json()["blue"]);
        // Blocks 2..5 alone are the run of --first-match 2 --matches 3.
        let tail = EvalReport::merge(&[label("b", &b), label("c", &c)]).unwrap();
        assert_eq!(tail.records, block(2, 3).records);
        assert!(tail
            .table()
            .starts_with("3 matches (numbers 2 to 4 of the evaluation)"));

        let err = |parts: &[(String, EvalReport)]| EvalReport::merge(parts).unwrap_err();
        assert!(matches!(
            err(&[label("a", &a), label("c", &c)]),
            ReportError::Gap { from: 2, to: 3, .. }
        ));
        assert!(matches!(
            err(&[label("a", &a), label("a2", &block(1, 2)), label("c", &c)]),
            ReportError::Overlap { index: 1, .. }
        ));
        let mut other = b.clone();
        other.names[1] = "idle".into();
        assert!(matches!(
            err(&[label("a", &a), label("b", &other)]),
            ReportError::Mismatch { field: "--red", .. }
        ));
        other = b.clone();
        other.config_hash ^= 1;
        assert!(matches!(
            err(&[label("a", &a), label("b", &other)]),
            ReportError::Mismatch {
                field: "config_hash",
                ..
            }
        ));
        assert!(matches!(err(&[]), ReportError::Empty));
        // A record that is not its plan's match is refused on reading.
        let mut json = b.to_json();
        json["results"][0]["seed"] = json!(1);
        assert!(matches!(
            EvalReport::from_json("b", &json),
            Err(ReportError::Format { .. })
        ));
        let mut json = b.to_json();
        json.as_object_mut().unwrap().remove("results");
        assert!(EvalReport::from_json("b", &json).is_err());
        // Another match length is another configuration.
        let longer = MatchConfig {
            minutes: 0.5,
            ..cfg.clone()
        };
        assert_ne!(config_hash(&longer), config_hash(&cfg));
    }

    #[test]
    fn confidence_interval_uses_student_t() {
        let e = Estimate::of(&[1.0, 2.0, 3.0]);
        assert!((e.mean - 2.0).abs() < 1e-12);
        // sd 1, n 3, t(2) = 4.303.
        assert!((e.ci95 - 4.303 / 3f64.sqrt()).abs() < 1e-9);
        assert!(Estimate::of(&[5.0]).ci95.is_nan());
        assert_eq!(t95(1000), 1.96);
    }
}
