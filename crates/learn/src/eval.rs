//! Evaluation: many whole matches between two teams, each a built-in policy
//! or a trained network, and the paper's Table I (average goals, ball-control
//! rate, average passes) plus shots and win/draw/loss, with 95% confidence
//! intervals over matches.
//!
//! Matches run side by side; a trained team decides for all its robots in all
//! matches in one forward pass per tick.

use naosoccer_client::{Policy, PolicyKind};
use naosoccer_proto::{Action, MatchStats, Observation, RobotId, Team, PLAYERS_PER_TEAM, ROBOTS};
use naosoccer_referee::{Match, MatchConfig};

use crate::env::episode_seed;
use crate::obs::OBS_DIM;
use crate::policy::{sample_uniform, LearnedPolicy};
use crate::LearnError;

/// One side of an evaluation.
pub enum Side {
    Builtin(PolicyKind),
    Learned(Box<LearnedPolicy>),
}

impl Side {
    /// `scripted` | `scripted:KEY=VAL,...` | `scripted:FILE.toml` | `random`
    /// | `idle` | `ppo:DIR` | `dqn:DIR` (and the other trained-team specs).
    pub fn parse(spec: &str) -> Result<Side, LearnError> {
        if !naosoccer_client::is_builtin_spec(spec) {
            return Ok(Side::Learned(Box::new(LearnedPolicy::load(spec)?)));
        }
        spec.parse::<PolicyKind>()
            .map(Side::Builtin)
            .map_err(|e| LearnError::Spec {
                spec: spec.to_string(),
                reason: format!("{e}; or ppo:DIR, dqn:DIR"),
            })
    }
}

/// One finished match.
#[derive(Debug, Clone, PartialEq)]
pub struct MatchResult {
    pub seed: u64,
    pub score: (u32, u32),
    pub stats: MatchStats,
    pub state_hash: u64,
}

struct Slot {
    m: Match,
    obs: Vec<Observation>,
    policies: Vec<Option<Box<dyn Policy>>>,
    decided: [Action; ROBOTS],
}

/// Plays `matches` whole matches, blue against red; match `i` has seed
/// `episode_seed(seed, i, 0)`.
pub fn play_matches(
    cfg: &MatchConfig,
    blue: &mut Side,
    red: &mut Side,
    matches: usize,
    seed: u64,
    threads: usize,
) -> Result<Vec<MatchResult>, LearnError> {
    let mut slots = Vec::with_capacity(matches);
    for i in 0..matches {
        let m = Match::new(cfg, episode_seed(seed, i, 0))?;
        let s = m.seed();
        let policies = RobotId::all()
            .map(|r| {
                let side = if r.team() == Team::Blue {
                    &*blue
                } else {
                    &*red
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
            m,
        };
        observe_all(&mut slot);
        slots.push(slot);
    }
    let mut feats = Vec::new();
    let mut players = Vec::new();
    let mut uniforms = Vec::new();
    let mut acts = Vec::new();
    while slots.iter().any(|s| !s.m.is_finished()) {
        for (team, side) in [(Team::Blue, &mut *blue), (Team::Red, &mut *red)] {
            let Side::Learned(policy) = side else {
                continue;
            };
            let live: Vec<usize> = (0..slots.len())
                .filter(|&i| !slots[i].m.is_finished())
                .collect();
            let n = live.len() * PLAYERS_PER_TEAM;
            feats.resize(n * OBS_DIM, 0.0);
            players.clear();
            uniforms.clear();
            acts.resize(n, 0usize);
            let scale = policy.scale();
            for (j, &i) in live.iter().enumerate() {
                for p in 0..PLAYERS_PER_TEAM {
                    let row = j * PLAYERS_PER_TEAM + p;
                    let obs = &slots[i].obs[team.index() * PLAYERS_PER_TEAM + p];
                    scale.encode(obs, &mut feats[row * OBS_DIM..(row + 1) * OBS_DIM]);
                    players.push(p);
                    // Keyed as a policy playing this one match would key it.
                    uniforms.push(sample_uniform(slots[i].m.seed(), team.index(), p, obs.tick));
                }
            }
            policy.act_rows_keyed(&feats, &players, &uniforms, &mut acts);
            for (j, &i) in live.iter().enumerate() {
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
        })
        .collect())
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
}

/// Table I over a set of matches, for both teams.
pub fn summarise(results: &[MatchResult], blue_name: &str, red_name: &str) -> [TeamSummary; 2] {
    Team::BOTH.map(|team| {
        let col = |f: &dyn Fn(&MatchResult) -> f64| {
            Estimate::of(&results.iter().map(f).collect::<Vec<_>>())
        };
        let mine = |r: &MatchResult| {
            if team == Team::Blue {
                r.score.0
            } else {
                r.score.1
            }
        };
        let theirs = |r: &MatchResult| {
            if team == Team::Blue {
                r.score.1
            } else {
                r.score.0
            }
        };
        TeamSummary {
            name: if team == Team::Blue {
                blue_name
            } else {
                red_name
            }
            .to_string(),
            goals: col(&|r| f64::from(mine(r))),
            control_rate: col(&|r| 100.0 * r.stats.team(team).control_rate),
            passes: col(&|r| f64::from(r.stats.team(team).passes)),
            shots: col(&|r| f64::from(r.stats.team(team).shots)),
            wins: results.iter().filter(|r| mine(r) > theirs(r)).count(),
            draws: results.iter().filter(|r| mine(r) == theirs(r)).count(),
            losses: results.iter().filter(|r| mine(r) < theirs(r)).count(),
        }
    })
}

/// The table as text, one row per team.
pub fn format_table(rows: &[TeamSummary], matches: usize) -> String {
    let mut s = format!(
        "{matches} matches, mean ± 95% CI\n{:<28} {:>14} {:>18} {:>16} {:>16} {:>11}\n",
        "team", "average goals", "ball control %", "average passes", "average shots", "W/D/L"
    );
    for r in rows {
        s.push_str(&format!(
            "{:<28} {:>14} {:>18} {:>16} {:>16} {:>11}\n",
            r.name,
            format!("{:.2}", r.goals),
            format!("{:.1}", r.control_rate),
            format!("{:.2}", r.passes),
            format!("{:.2}", r.shots),
            format!("{}/{}/{}", r.wins, r.draws, r.losses)
        ));
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

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
