//! An evaluation's report: its JSON (`eval --json`), read back and merged
//! (`eval --merge`), and its table.

use naosoccer_referee::MatchConfig;
use serde::Deserialize;
use serde_json::{json, Value};

use super::{
    format_table, summarise, Estimate, EvalPlan, MatchRecord, MatchResult, Rate, Record,
    SeedScheme, TeamSummary,
};

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
                "passes": est(&r.passes), "aimed_passes": est(&r.aimed_passes),
                "long_passes": est(&r.long_passes), "shots": est(&r.shots),
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
