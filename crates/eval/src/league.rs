//! A league: every pair of teams plays an evaluation ([`crate::eval`]) with
//! the sides swapped in every other match, and all the results are fitted
//! to one Bradley–Terry rating per team.
//!
//! Pair `(i, j)`, `i < j` in the order the teams were given, is the
//! evaluation `eval --blue TEAM_i --red TEAM_j --matches M --seed S
//! --both-sides`: every pair plays the same match seeds, and its report is
//! exactly that evaluation's (so a pair's results can be replayed, merged
//! or checked with `eval`). The Python league (`python -m naosoccer.ray
//! league`, `naosoccer.league`) plays the same pairs and fits the same
//! model, so both give the same table for the same results.
//!
//! The rating is the maximum of the Bradley–Terry posterior: strengths
//! `theta` with P(i beats j) = 1 / (1 + exp(theta_j - theta_i)); a draw
//! counts as half a win for each side, and every pair that met gets
//! [`PRIOR_DRAWS`] virtual draws (a weak prior that keeps a team that won
//! every match at a finite rating). Ratings are on the Elo scale,
//! `400 log10(e) theta` (400 points: odds of 10 to 1), with mean 0. The 95%
//! interval is ±1.96 standard errors from the curvature of the log
//! posterior at its maximum (the Laplace approximation): deterministic, and
//! narrower the more matches were played.

use serde_json::{json, Value};

use crate::eval::{EvalReport, MatchRecord, Record};

/// Elo points per unit of Bradley–Terry log-strength.
pub const ELO_PER_NAT: f64 = 400.0 / std::f64::consts::LN_10;
/// Virtual draws added to every pair that met (the prior).
pub const PRIOR_DRAWS: f64 = 1.0;

/// The round robin's pairs of `n` teams: `(i, j)`, `i < j`, `i` playing
/// `--blue` (and red in the swapped matches).
pub fn pairings(n: usize) -> Vec<(usize, usize)> {
    (0..n)
        .flat_map(|i| (i + 1..n).map(move |j| (i, j)))
        .collect()
}

/// A Bradley–Terry fit: log-strengths (mean 0) and their standard errors.
#[derive(Debug, Clone, PartialEq)]
pub struct Fit {
    pub theta: Vec<f64>,
    pub se: Vec<f64>,
}

/// Fits the model to `scores`, an `n` x `n` matrix where `scores[i][j]` is
/// what team `i` scored against `j` (a win 1, a draw 1/2); every pair that
/// met gets `prior_draws` virtual draws. Newton's method on the log
/// posterior, each step solved with the information matrix's
/// pseudo-inverse (strengths are defined up to a constant, fixed by
/// centring them). Teams that met nobody get strength 0 and an infinite
/// error.
pub fn bradley_terry(scores: &[Vec<f64>], prior_draws: f64) -> Fit {
    let n = scores.len();
    let w: Vec<Vec<f64>> = (0..n)
        .map(|i| {
            (0..n)
                .map(|j| {
                    let met = scores[i][j] + scores[j][i] > 0.0;
                    scores[i][j] + if met { prior_draws / 2.0 } else { 0.0 }
                })
                .collect()
        })
        .collect();
    let games = |i: usize, j: usize| w[i][j] + w[j][i];
    let mut theta: Vec<f64> = vec![0.0; n];
    let info = |theta: &[f64]| {
        let mut m = vec![vec![0.0; n]; n];
        for i in 0..n {
            for j in 0..n {
                if i != j {
                    let p = 1.0 / (1.0 + (theta[j] - theta[i]).exp());
                    let c = games(i, j) * p * (1.0 - p);
                    m[i][j] -= c;
                    m[i][i] += c;
                }
            }
        }
        m
    };
    for _ in 0..200 {
        let grad: Vec<f64> = (0..n)
            .map(|i| {
                (0..n)
                    .filter(|&j| j != i)
                    .map(|j| w[i][j] - games(i, j) / (1.0 + (theta[j] - theta[i]).exp()))
                    .sum()
            })
            .collect();
        let step = mul(&pseudo_inverse(&info(&theta)), &grad);
        for (t, s) in theta.iter_mut().zip(&step) {
            *t += s;
        }
        let mean = theta.iter().sum::<f64>() / n.max(1) as f64;
        theta.iter_mut().for_each(|t| *t -= mean);
        if step.iter().all(|s| s.abs() < 1e-12) {
            break;
        }
    }
    let cov = pseudo_inverse(&info(&theta));
    let se = (0..n)
        .map(|i| {
            let met = (0..n).any(|j| j != i && games(i, j) > 0.0);
            if met {
                cov[i][i].max(0.0).sqrt()
            } else {
                f64::INFINITY
            }
        })
        .collect();
    Fit { theta, se }
}

/// The Moore–Penrose inverse of a symmetric matrix whose null space is the
/// constant vectors of its connected blocks: as `numpy.linalg.pinv` gives
/// it. Each connected block `L` (teams linked by matches) is inverted as
/// `(L + J/k)^-1 - J/k`, `J` the block's all-ones matrix, `k` its size.
fn pseudo_inverse(m: &[Vec<f64>]) -> Vec<Vec<f64>> {
    let n = m.len();
    let mut block = vec![usize::MAX; n];
    for start in 0..n {
        if block[start] != usize::MAX {
            continue;
        }
        let mut stack = vec![start];
        block[start] = start;
        while let Some(i) = stack.pop() {
            for j in 0..n {
                if j != i && m[i][j] != 0.0 && block[j] == usize::MAX {
                    block[j] = start;
                    stack.push(j);
                }
            }
        }
    }
    let mut out = vec![vec![0.0; n]; n];
    for b in 0..n {
        let idx: Vec<usize> = (0..n).filter(|&i| block[i] == b).collect();
        let k = idx.len();
        if k == 0 || (k == 1 && m[idx[0]][idx[0]] == 0.0) {
            continue;
        }
        let kf = k as f64;
        let mut a: Vec<Vec<f64>> = idx
            .iter()
            .map(|&i| idx.iter().map(|&j| m[i][j] + 1.0 / kf).collect())
            .collect();
        let inv = invert(&mut a);
        for (r, &i) in idx.iter().enumerate() {
            for (c, &j) in idx.iter().enumerate() {
                out[i][j] = inv[r][c] - 1.0 / kf;
            }
        }
    }
    out
}

/// Gauss–Jordan with partial pivoting (the matrix is positive definite
/// here, so a pivot never vanishes).
fn invert(a: &mut [Vec<f64>]) -> Vec<Vec<f64>> {
    let n = a.len();
    let mut inv: Vec<Vec<f64>> = (0..n)
        .map(|i| (0..n).map(|j| f64::from(u8::from(i == j))).collect())
        .collect();
    for col in 0..n {
        let pivot = (col..n)
            .max_by(|&x, &y| a[x][col].abs().total_cmp(&a[y][col].abs()))
            .unwrap_or(col);
        a.swap(col, pivot);
        inv.swap(col, pivot);
        let d = a[col][col];
        for j in 0..n {
            a[col][j] /= d;
            inv[col][j] /= d;
        }
        for r in 0..n {
            if r != col {
                let f = a[r][col];
                if f != 0.0 {
                    for j in 0..n {
                        a[r][j] -= f * a[col][j];
                        inv[r][j] -= f * inv[col][j];
                    }
                }
            }
        }
    }
    inv
}

fn mul(m: &[Vec<f64>], v: &[f64]) -> Vec<f64> {
    m.iter()
        .map(|row| row.iter().zip(v).map(|(a, b)| a * b).sum())
        .collect()
}

/// Goals a team scored, by how they came (the referee's `TeamStats`):
/// from open play, from the team's own kick-off or set play, and the other
/// team's own goals.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct PhaseGoals {
    pub open_play: u64,
    pub restart: u64,
    pub own_goal: u64,
}

/// One team's line of the league table.
#[derive(Debug, Clone, PartialEq)]
pub struct Standing {
    /// Its spec, as given.
    pub team: String,
    pub record: Record,
    pub goals_for: u64,
    pub goals_against: u64,
    /// Its goals for, by phase.
    pub phases: PhaseGoals,
    /// Elo scale, mean 0 over the league.
    pub rating: f64,
    /// The 95% interval.
    pub rating_low: f64,
    pub rating_high: f64,
}

impl Standing {
    /// Three points a win, one a draw.
    pub fn points(&self) -> usize {
        3 * self.record.wins + self.record.draws
    }
}

/// Why a league's results do not fit together.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum LeagueError {
    #[error("a league needs at least two teams, got {0}")]
    TooFewTeams(usize),
    #[error("team {0:?} is named twice")]
    Duplicate(String),
    #[error("{teams} teams play {pairs} pairs, got {got} evaluations")]
    PairCount {
        teams: usize,
        pairs: usize,
        got: usize,
    },
    #[error("pair {index} is {found}, expected {expected}")]
    WrongPair {
        index: usize,
        expected: String,
        found: String,
    },
}

/// A played league: the teams, and one evaluation per pair in
/// [`pairings`] order.
#[derive(Debug, Clone, PartialEq)]
pub struct League {
    pub teams: Vec<String>,
    pub pairs: Vec<EvalReport>,
}

impl League {
    /// Checks that `pairs` are the round robin of `teams`.
    pub fn new(teams: Vec<String>, pairs: Vec<EvalReport>) -> Result<League, LeagueError> {
        check_teams(&teams)?;
        let order = pairings(teams.len());
        if pairs.len() != order.len() {
            return Err(LeagueError::PairCount {
                teams: teams.len(),
                pairs: order.len(),
                got: pairs.len(),
            });
        }
        for (index, ((i, j), r)) in order.iter().zip(&pairs).enumerate() {
            if r.names[0] != teams[*i] || r.names[1] != teams[*j] {
                return Err(LeagueError::WrongPair {
                    index,
                    expected: format!("{} v {}", teams[*i], teams[*j]),
                    found: format!("{} v {}", r.names[0], r.names[1]),
                });
            }
        }
        Ok(League { teams, pairs })
    }

    /// The table, best rating first (then goal difference, then the order
    /// given).
    pub fn standings(&self) -> Vec<Standing> {
        let n = self.teams.len();
        let mut rows: Vec<Standing> = self
            .teams
            .iter()
            .map(|t| Standing {
                team: t.clone(),
                record: Record::default(),
                goals_for: 0,
                goals_against: 0,
                phases: PhaseGoals::default(),
                rating: 0.0,
                rating_low: 0.0,
                rating_high: 0.0,
            })
            .collect();
        let mut scores = vec![vec![0.0; n]; n];
        for ((i, j), report) in pairings(n).into_iter().zip(&self.pairs) {
            for r in &report.records {
                for (k, team, other) in [(0, i, j), (1, j, i)] {
                    let (own, opp) = (r.goals[k], r.goals[1 - k]);
                    let row = &mut rows[team];
                    row.goals_for += u64::from(own);
                    row.goals_against += u64::from(opp);
                    let p = phase_goals(r, k);
                    row.phases.open_play += p.open_play;
                    row.phases.restart += p.restart;
                    row.phases.own_goal += p.own_goal;
                    match own.cmp(&opp) {
                        std::cmp::Ordering::Greater => {
                            row.record.wins += 1;
                            scores[team][other] += 1.0;
                        }
                        std::cmp::Ordering::Equal => {
                            row.record.draws += 1;
                            scores[team][other] += 0.5;
                        }
                        std::cmp::Ordering::Less => row.record.losses += 1,
                    }
                }
            }
        }
        let fit = bradley_terry(&scores, PRIOR_DRAWS);
        for (k, row) in rows.iter_mut().enumerate() {
            row.rating = fit.theta[k] * ELO_PER_NAT;
            let half = 1.96 * fit.se[k] * ELO_PER_NAT;
            row.rating_low = row.rating - half;
            row.rating_high = row.rating + half;
        }
        let mut order: Vec<usize> = (0..n).collect();
        let diff = |s: &Standing| s.goals_for as i64 - s.goals_against as i64;
        order.sort_by(|&a, &b| {
            // Ratings equal to rounding are a tie.
            let ra = (rows[a].rating * 1e6).round();
            let rb = (rows[b].rating * 1e6).round();
            rb.total_cmp(&ra)
                .then(diff(&rows[b]).cmp(&diff(&rows[a])))
                .then(a.cmp(&b))
        });
        order.into_iter().map(|k| rows[k].clone()).collect()
    }

    /// The `league --json` object: settings, standings (best first), and
    /// every pair's `eval --json` object.
    pub fn to_json(&self, wall_seconds: f64) -> Value {
        let first = self.pairs.first();
        let standings: Vec<Value> = self
            .standings()
            .iter()
            .enumerate()
            .map(|(rank, s)| {
                json!({
                    "rank": rank + 1, "team": s.team, "matches": s.record.matches(),
                    "wins": s.record.wins, "draws": s.record.draws, "losses": s.record.losses,
                    "goals_for": s.goals_for, "goals_against": s.goals_against,
                    "goal_difference": s.goals_for as i64 - s.goals_against as i64,
                    "goals_open_play": s.phases.open_play, "goals_restart": s.phases.restart,
                    "goals_own_goal": s.phases.own_goal,
                    "points": s.points(), "rating": s.rating,
                    "rating_low": s.rating_low, "rating_high": s.rating_high,
                })
            })
            .collect();
        json!({
            "teams": self.teams,
            "matches_per_pairing": first.map(|r| r.plan.matches),
            "seed": first.map(|r| r.plan.seed),
            "both_sides": true,
            "minutes": first.map(|r| r.minutes),
            "rating": {
                "model": "bradley-terry",
                "scale": "elo",
                "prior_draws_per_pairing": PRIOR_DRAWS,
                "interval": "95% (1.96 standard errors, Laplace)",
            },
            "standings": standings,
            "pairings": self.pairs.iter().map(|r| {
                let mut v = r.to_json();
                if let Some(o) = v.as_object_mut() {
                    o.remove("wall_seconds");
                }
                v
            }).collect::<Vec<_>>(),
            "wall_seconds": wall_seconds,
        })
    }

    /// The table `naosoccer league` prints: the standings, then each pair.
    pub fn table(&self) -> String {
        let first = &self.pairs[0];
        let width = self.teams.iter().map(|t| t.len()).max().unwrap_or(4).max(4);
        let mut s = format!(
            "League of {} teams: round robin, {} matches a pair (every other one with the \
             sides swapped), seed {}, {:.1} min matches\n",
            self.teams.len(),
            first.plan.matches,
            first.plan.seed,
            first.minutes
        );
        s.push_str(&format!(
            "{:>2} {:<width$} {:>7} {:>16} {:>11} {:>6} {:>9} {:>22}\n",
            "#",
            "team",
            "rating",
            "95% interval",
            "W/D/L",
            "points",
            "goals",
            "open play/restart/own"
        ));
        for (rank, r) in self.standings().iter().enumerate() {
            s.push_str(&format!(
                "{:>2} {:<width$} {:>7} {:>16} {:>11} {:>6} {:>9} {:>22}\n",
                rank + 1,
                r.team,
                signed(r.rating),
                format!("[{}, {}]", signed(r.rating_low), signed(r.rating_high)),
                format!("{}/{}/{}", r.record.wins, r.record.draws, r.record.losses),
                r.points(),
                format!("{}:{}", r.goals_for, r.goals_against),
                format!(
                    "{}/{}/{}",
                    r.phases.open_play, r.phases.restart, r.phases.own_goal
                ),
            ));
        }
        s.push_str(
            "pairs (W/D/L and goals of the first team; win % with its Wilson 95% interval):\n",
        );
        for r in &self.pairs {
            let [a, _] = r.summary();
            let (gf, ga) = r.records.iter().fold((0u64, 0u64), |(f, g), m| {
                (f + u64::from(m.goals[0]), g + u64::from(m.goals[1]))
            });
            s.push_str(&format!(
                "  {} v {}: {}/{}/{}, goals {gf}:{ga}, win % {}\n",
                r.names[0], r.names[1], a.wins, a.draws, a.losses, a.win_rate
            ));
        }
        s.push_str(
            "Ratings: Bradley–Terry on the Elo scale (mean 0), a draw half a win, one virtual \
             draw a pair as the prior; intervals ±1.96 standard errors.\n",
        );
        s
    }
}

fn check_teams(teams: &[String]) -> Result<(), LeagueError> {
    if teams.len() < 2 {
        return Err(LeagueError::TooFewTeams(teams.len()));
    }
    for (k, t) in teams.iter().enumerate() {
        if teams[..k].contains(t) {
            return Err(LeagueError::Duplicate(t.clone()));
        }
    }
    Ok(())
}

/// Checks a league's team list before anything is played: at least two
/// teams, none named twice.
pub fn check_team_list(teams: &[String]) -> Result<(), LeagueError> {
    check_teams(teams)
}

/// The goals by phase of the first team (`k` = 0) or the second of a match
/// (0 in reports written before the referee counted them).
fn phase_goals(r: &MatchRecord, k: usize) -> PhaseGoals {
    PhaseGoals {
        open_play: u64::from(r.goals_open_play[k]),
        restart: u64::from(r.goals_restart[k]),
        own_goal: u64::from(r.goals_own_goal[k]),
    }
}

fn signed(x: f64) -> String {
    if x.round() == 0.0 {
        "0".into()
    } else {
        format!("{x:+.0}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Scores from `wins[i][j]` wins of i over j and `draws[i][j]` draws.
    fn scores(wins: &[Vec<u32>], draws: &[Vec<u32>]) -> Vec<Vec<f64>> {
        let n = wins.len();
        (0..n)
            .map(|i| {
                (0..n)
                    .map(|j| f64::from(wins[i][j]) + 0.5 * f64::from(draws[i][j]))
                    .collect()
            })
            .collect()
    }

    /// A ladder of `n` teams where team i beats team j < i in `p(i - j)`
    /// of `m` matches and loses the rest.
    // Both halves of the table are written at once: indices say it best.
    #[allow(clippy::needless_range_loop)]
    fn ladder(n: usize, m: u32, p: impl Fn(usize) -> f64) -> Vec<Vec<f64>> {
        let mut wins = vec![vec![0u32; n]; n];
        for i in 0..n {
            for j in 0..i {
                let w = (p(i - j) * f64::from(m)).round() as u32;
                wins[i][j] = w;
                wins[j][i] = m - w;
            }
        }
        scores(&wins, &vec![vec![0; n]; n])
    }

    #[test]
    fn a_clear_ordering_is_recovered() {
        let fit = bradley_terry(&ladder(5, 100, |gap| 0.6 + 0.1 * gap as f64), PRIOR_DRAWS);
        for k in 1..5 {
            assert!(fit.theta[k] > fit.theta[k - 1], "{fit:?}");
        }
        assert!(fit.theta.iter().sum::<f64>().abs() < 1e-9);
    }

    #[test]
    fn two_teams_match_the_closed_form() {
        // 70 wins, 30 losses, plus one virtual draw: theta_1 - theta_0 =
        // ln(70.5 / 30.5); the variance of the difference is
        // 1 / (games p (1 - p)), split evenly between the two.
        let s = vec![vec![0.0, 30.0], vec![70.0, 0.0]];
        let fit = bradley_terry(&s, 1.0);
        let d = (70.5f64 / 30.5).ln();
        assert!((fit.theta[1] - fit.theta[0] - d).abs() < 1e-9, "{fit:?}");
        let p = 70.5 / 101.0;
        let var_diff: f64 = 1.0 / (101.0 * p * (1.0 - p));
        let se = (var_diff / 4.0).sqrt();
        assert!((fit.se[0] - se).abs() < 1e-9 && (fit.se[1] - se).abs() < 1e-9);
    }

    #[test]
    fn intervals_shrink_with_more_matches() {
        let few = bradley_terry(&ladder(4, 20, |_| 0.75), PRIOR_DRAWS);
        let many = bradley_terry(&ladder(4, 200, |_| 0.75), PRIOR_DRAWS);
        for k in 0..4 {
            assert!(many.se[k] < few.se[k] / 2.0, "{few:?} {many:?}");
        }
        // Ten times the matches at the same rates: about the same strengths.
        for k in 0..4 {
            assert!((many.theta[k] - few.theta[k]).abs() < 0.1);
        }
    }

    #[test]
    fn a_team_that_wins_everything_stays_finite_and_a_stranger_is_unrated() {
        let mut s = ladder(3, 10, |_| 1.0);
        let fit = bradley_terry(&s, PRIOR_DRAWS);
        assert!(fit.theta.iter().all(|t| t.is_finite()));
        assert!(fit.theta[2] > fit.theta[1] && fit.theta[1] > fit.theta[0]);
        // A fourth team that met nobody.
        for row in &mut s {
            row.push(0.0);
        }
        s.push(vec![0.0; 4]);
        let fit = bradley_terry(&s, PRIOR_DRAWS);
        assert!(fit.theta[3].abs() < 1e-12);
        assert!(fit.se[3].is_infinite() && fit.se[0].is_finite());
    }

    #[test]
    fn pairs_and_team_lists_are_checked() {
        assert_eq!(pairings(3), vec![(0, 1), (0, 2), (1, 2)]);
        let names = |v: &[&str]| v.iter().map(|s| s.to_string()).collect::<Vec<_>>();
        assert!(matches!(
            check_team_list(&names(&["a"])),
            Err(LeagueError::TooFewTeams(1))
        ));
        let e = check_team_list(&names(&["a", "b", "a"])).unwrap_err();
        assert_eq!(e.to_string(), "team \"a\" is named twice");
        assert!(matches!(
            League::new(names(&["a", "b"]), vec![]),
            Err(LeagueError::PairCount { .. })
        ));
    }
}
