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

use naosoccer_client::{Policy, PolicyKind};
use naosoccer_proto::{
    Action, MatchStats, Observation, RobotId, Score, Team, PLAYERS_PER_TEAM, ROBOTS,
};
use naosoccer_referee::{Match, MatchConfig};

use crate::learned::LearnedPolicy;
use crate::PolicyError;

/// One side of an evaluation.
pub enum Side {
    Builtin(PolicyKind),
    Learned(Box<LearnedPolicy>),
}

impl Side {
    /// `scripted` | `scripted:KEY=VAL,...` | `scripted:FILE.toml` | `random`
    /// | `idle` | `ppo:DIR` | `dqn:DIR` (and the other trained-team specs).
    pub fn parse(spec: &str) -> Result<Side, PolicyError> {
        if !naosoccer_client::is_builtin_spec(spec) {
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

/// How an evaluation is played.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct EvalPlan {
    pub matches: usize,
    pub seed: u64,
    /// Odd-numbered matches swap the sides: the first team plays red.
    pub both_sides: bool,
    pub seeds: SeedScheme,
}

impl EvalPlan {
    /// Whether match `i` has the first team playing red.
    pub fn swapped(&self, i: usize) -> bool {
        self.both_sides && i % 2 == 1
    }
}

/// One finished match.
#[derive(Debug, Clone, PartialEq)]
pub struct MatchResult {
    pub seed: u64,
    /// By colour.
    pub score: Score,
    pub stats: MatchStats,
    pub state_hash: u64,
    /// The first team (`--blue`) played red.
    pub swapped: bool,
}

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
}

struct Slot {
    m: Match,
    obs: Vec<Observation>,
    policies: Vec<Option<Box<dyn Policy>>>,
    decided: [Action; ROBOTS],
    swapped: bool,
}

/// Plays the matches of `plan` between `first` and `second`: match `i` has
/// seed `plan.seeds.match_seed(plan.seed, i)`, and `first` plays blue unless
/// `plan.swapped(i)`.
pub fn play_matches(
    cfg: &MatchConfig,
    first: &mut Side,
    second: &mut Side,
    plan: &EvalPlan,
    threads: usize,
) -> Result<Vec<MatchResult>, PolicyError> {
    let mut slots = Vec::with_capacity(plan.matches);
    for i in 0..plan.matches {
        let m = Match::new(cfg, plan.seeds.match_seed(plan.seed, i))?;
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
            swapped,
            m,
        };
        observe_all(&mut slot);
        slots.push(slot);
    }
    let mut acts = Vec::new();
    while slots.iter().any(|s| !s.m.is_finished()) {
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
                for p in 0..PLAYERS_PER_TEAM {
                    let a =
                        Action::from_index(acts[j * PLAYERS_PER_TEAM + p]).unwrap_or(Action::Stay);
                    slots[i].decided[team.index() * PLAYERS_PER_TEAM + p] = a;
                }
            }
        }
        let threads = threads.clamp(1, slots.len().max(1));
        let per = slots.len().div_ceil(threads).max(1);
        if threads == 1 {
            slots.iter_mut().for_each(step_slot);
        } else {
            std::thread::scope(|s| {
                for chunk in slots.chunks_mut(per) {
                    s.spawn(move || chunk.iter_mut().for_each(step_slot));
                }
            });
        }
    }
    Ok(slots
        .iter()
        .map(|s| MatchResult {
            seed: s.m.seed(),
            score: s.m.score(),
            stats: s.m.stats(),
            state_hash: s.m.state_hash(),
            swapped: s.swapped,
        })
        .collect())
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

fn step_slot(slot: &mut Slot) {
    if slot.m.is_finished() {
        return;
    }
    for (i, p) in slot.policies.iter_mut().enumerate() {
        if let Some(p) = p {
            slot.decided[i] = p.act(&slot.obs[i]);
        }
    }
    slot.m.step(&slot.decided);
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
    pub shots: Estimate,
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
/// second, each under its own name whichever colour it played.
pub fn summarise(results: &[MatchResult], first_name: &str, second_name: &str) -> [TeamSummary; 2] {
    [(true, first_name), (false, second_name)].map(|(first, name)| {
        let col = |f: &dyn Fn(&MatchResult) -> f64| {
            Estimate::of(&results.iter().map(f).collect::<Vec<_>>())
        };
        let (mut as_blue, mut as_red) = (Record::default(), Record::default());
        for r in results {
            let rec = if r.team_of(first) == Team::Blue {
                &mut as_blue
            } else {
                &mut as_red
            };
            match r.goals_of(first).cmp(&r.goals_of(!first)) {
                std::cmp::Ordering::Greater => rec.wins += 1,
                std::cmp::Ordering::Equal => rec.draws += 1,
                std::cmp::Ordering::Less => rec.losses += 1,
            }
        }
        let wins = as_blue.wins + as_red.wins;
        TeamSummary {
            name: name.to_string(),
            goals: col(&|r| f64::from(r.goals_of(first))),
            control_rate: col(&|r| 100.0 * r.stats.team(r.team_of(first)).control_rate),
            passes: col(&|r| f64::from(r.stats.team(r.team_of(first)).passes)),
            shots: col(&|r| f64::from(r.stats.team(r.team_of(first)).shots)),
            wins,
            draws: as_blue.draws + as_red.draws,
            losses: as_blue.losses + as_red.losses,
            win_rate: Rate::wilson(wins, results.len()),
            as_blue,
            as_red,
        }
    })
}

/// The table as text, one row per team.
pub fn format_table(rows: &[TeamSummary], matches: usize) -> String {
    let both = rows
        .iter()
        .any(|r| r.as_red.matches() > 0 && r.as_blue.matches() > 0);
    let mut s = format!(
        "{matches} matches{}, mean ± 95% CI; win % with its Wilson 95% interval\n\
         {:<28} {:>14} {:>18} {:>16} {:>16} {:>11} {:>20}\n",
        if both {
            ", half with the sides swapped"
        } else {
            ""
        },
        "team",
        "average goals",
        "ball control %",
        "average passes",
        "average shots",
        "W/D/L",
        "win %"
    );
    for r in rows {
        s.push_str(&format!(
            "{:<28} {:>14} {:>18} {:>16} {:>16} {:>11} {:>20}\n",
            r.name,
            format!("{:.2}", r.goals),
            format!("{:.1}", r.control_rate),
            format!("{:.2}", r.passes),
            format!("{:.2}", r.shots),
            format!("{}/{}/{}", r.wins, r.draws, r.losses),
            r.win_rate.to_string(),
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
        let [first, second] = summarise(&both, "scripted", "random");
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
