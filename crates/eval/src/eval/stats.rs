//! The statistics of a set of matches: means with Student-t 95% intervals,
//! rates with Wilson intervals, and each team's row of Table I.

use super::MatchRecord;

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
    /// Passes whose kick was a `pass` swung toward a receiver.
    pub aimed_passes: Estimate,
    /// Passes of at least [`LONG_PASS_METRES`](super::LONG_PASS_METRES).
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
            aimed_passes: col(&|r| f64::from(r.aimed_passes[k])),
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
