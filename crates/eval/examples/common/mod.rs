//! What the examples that play a team against an opponent over match
//! seeds 1..=N share: their command line, playing one of those matches,
//! the distance bins' labels and the percentages they print.

// Each example compiles this module for itself and uses a part of it.
#![allow(dead_code)]

use std::ops::ControlFlow;
use std::process::ExitCode;

use naosoccer_eval::run::{play_one, Fixture, Side, Ticked};
use naosoccer_referee::MatchConfig;

/// `TEAM OPPONENT MATCHES` from the command line; `Err` (after a message
/// naming the example) on anything else.
pub fn team_opponent_matches(example: &str) -> Result<(String, String, u64), ExitCode> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    match args.as_slice() {
        [t, o, n] => match n.parse::<u64>() {
            Ok(n) if n > 0 => Ok((t.clone(), o.clone(), n)),
            _ => {
                eprintln!("MATCHES must be a positive integer, not {n:?}");
                Err(ExitCode::from(2))
            }
        },
        _ => {
            eprintln!("usage: {example} TEAM OPPONENT MATCHES  (teams as `eval` names them: ppo:DIR, scripted, ...)");
            Err(ExitCode::from(2))
        }
    }
}

/// The two sides of one match, fresh (a learned side's sampling starts
/// anew); `Err` after printing why one cannot be made.
pub fn sides(team: &str, opponent: &str) -> Result<(Side, Side), ExitCode> {
    match (Side::parse(team), Side::parse(opponent)) {
        (Ok(a), Ok(b)) => Ok((a, b)),
        (Err(e), _) | (_, Err(e)) => {
            eprintln!("{e}");
            Err(ExitCode::FAILURE)
        }
    }
}

/// Plays the kick-off match `seed` of fresh sides, `team` blue against
/// `opponent`, calling `watch` after every control tick; `Err` after
/// printing why it could not be played.
pub fn play_match(
    cfg: &MatchConfig,
    team: &str,
    opponent: &str,
    seed: u64,
    watch: impl FnMut(&Ticked<'_>) -> ControlFlow<()>,
) -> Result<(), ExitCode> {
    let (mut first, mut second) = sides(team, opponent)?;
    play_one(cfg, &mut first, &mut second, Fixture::kick_off(seed), watch)
        .map(|_| ())
        .map_err(|e| {
            eprintln!("{e}");
            ExitCode::FAILURE
        })
}

/// `k` of `n` in percent (0 when `n` is 0).
pub fn pct(k: u64, n: u64) -> f64 {
    100.0 * k as f64 / n.max(1) as f64
}

/// The labels of distance bins whose upper ends are `rows` (the first bin
/// starts at 0, the last may be open): `"1.0-2.0 m"`, `">=4.5 m"`.
pub fn bin_labels(rows: &[f32]) -> Vec<String> {
    let mut lo = 0.0;
    rows.iter()
        .map(|&hi| {
            let label = if hi.is_finite() {
                format!("{lo:.1}-{hi:.1} m")
            } else {
                format!(">={lo:.1} m")
            };
            lo = hi;
            label
        })
        .collect()
}
