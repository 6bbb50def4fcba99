//! `naosoccer league`: a round robin of evaluations between teams, built-in
//! or trained, and a Bradley–Terry rating fitted on all the results
//! (`naosoccer_eval::league`). The matches are played by the evaluation's
//! runner (`eval::play_matches`), in blocks so that a progress bar can
//! follow; a match's result does not depend on the block it was played in.

use std::io::{IsTerminal, Write};
use std::path::PathBuf;
use std::time::Instant;

use anyhow::Context;
use clap::Args;
use naosoccer_eval::eval::{play_matches, EvalPlan, EvalReport, SeedScheme, Side};
use naosoccer_eval::league::{check_team_list, pairings, League};

use super::eval::match_config;

#[derive(Args, Debug)]
#[command(after_help = "Examples:
  naosoccer league scripted:1 scripted:2 scripted:3 scripted:4 scripted:5 --matches 20
  naosoccer league scripted random idle ppo:assets/policies/ppo-team-seed1 --matches 50 --json
  naosoccer league scripted:5 scripted --minutes 2 --matches 10 --threads 2

Every pair of teams (i, j), i before j on the command line, plays the
evaluation `naosoccer eval --blue TEAM_i --red TEAM_j --matches N --seed S
--both-sides`: the same match seeds for every pair, every other match with
the sides swapped. A pair's results in --json are exactly that evaluation's
`eval --json` object (without wall_seconds), so any pair can be replayed
with `eval` alone.

The table ranks the teams by a Bradley–Terry rating fitted on all the
matches (P(i beats j) = 1 / (1 + exp(theta_j - theta_i)), a draw half a win
for each side, one virtual draw a pair as a weak prior), on the Elo scale
(400 points: odds of 10 to 1) with mean 0, and its 95% interval (±1.96
standard errors from the curvature at the maximum: deterministic, narrower
with more matches). It also gives wins/draws/losses, points (3 a win, 1 a
draw), goals for and against, and the goals for by phase: from open play,
from the team's own kick-off or set play, and the other team's own goals.
The same teams, --matches, --seed and match configuration always give the
same table, whatever --threads.

--json prints one object: the settings, \"standings\" (best first: rank,
team, matches, wins, draws, losses, goals_for, goals_against,
goal_difference, goals_open_play, goals_restart, goals_own_goal, points,
rating, rating_low, rating_high) and \"pairings\" (one `eval --json` object
a pair). `python -m naosoccer.ray league` plays the same league on a Ray
cluster and fits the same model (docs/RAY.md).

Team specs are those of `eval`: scripted, scripted:1 ... scripted:5 (the
ladder of built-in teams; scripted is scripted:3), scripted:KEY=VAL,...,
scripted:FILE.toml, random, idle, ppo:DIR, ppo-greedy:DIR, dqn:DIR,
dqn-epsilon:DIR.")]
pub struct LeagueArgs {
    /// The teams (at least two, each once), as `eval --blue` takes them.
    #[arg(required = true, num_args = 1.., value_name = "SPEC")]
    teams: Vec<String>,
    /// Matches per pair (every other one with the sides swapped).
    #[arg(long, default_value_t = 20)]
    matches: usize,
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Match configuration (TOML); default: the built-in assets/match.toml.
    #[arg(long)]
    config: Option<PathBuf>,
    /// Match length in minutes, overriding the configuration.
    #[arg(long)]
    minutes: Option<f32>,
    /// Threads stepping matches.
    #[arg(long, default_value_t = 2)]
    threads: usize,
    /// One JSON object instead of the table.
    #[arg(long)]
    json: bool,
    /// No progress bar on standard error.
    #[arg(long)]
    quiet: bool,
}

pub fn league_cmd(a: LeagueArgs) -> anyhow::Result<()> {
    anyhow::ensure!(a.matches > 0, "--matches must be at least 1");
    check_team_list(&a.teams)?;
    let cfg = match_config(a.config.as_ref(), a.minutes)?;
    // Every spec is checked (and every trained team loaded once) before a
    // match is played.
    for t in &a.teams {
        Side::parse(t).with_context(|| format!("team {t:?}"))?;
    }
    let pairs = pairings(a.teams.len());
    let total = pairs.len() * a.matches;
    let mut bar = Progress::new(total, !a.quiet);
    // Blocks of a few matches per thread: small enough for the bar to move,
    // large enough to keep the threads busy.
    let block = (4 * a.threads.max(1)).max(8);
    let start = Instant::now();
    let mut reports = Vec::with_capacity(pairs.len());
    for &(i, j) in &pairs {
        let (blue, red) = (&a.teams[i], &a.teams[j]);
        let pair_start = Instant::now();
        let mut first = Side::parse(blue)?;
        let mut second = Side::parse(red)?;
        let mut results = Vec::with_capacity(a.matches);
        let mut from = 0;
        while from < a.matches {
            let plan = EvalPlan {
                matches: block.min(a.matches - from),
                first_match: from,
                seed: a.seed,
                both_sides: true,
                seeds: SeedScheme::Eval,
            };
            results.extend(play_matches(
                &cfg,
                &mut first,
                &mut second,
                &plan,
                a.threads,
            )?);
            from += plan.matches;
            bar.advance(plan.matches, &format!("{blue} v {red}"), start);
        }
        let plan = EvalPlan {
            matches: a.matches,
            first_match: 0,
            seed: a.seed,
            both_sides: true,
            seeds: SeedScheme::Eval,
        };
        reports.push(EvalReport::new(
            [blue.clone(), red.clone()],
            plan,
            &cfg,
            &results,
            pair_start.elapsed().as_secs_f64(),
        ));
    }
    bar.finish();
    let league = League::new(a.teams.clone(), reports)?;
    if a.json {
        println!("{}", league.to_json(start.elapsed().as_secs_f64()));
    } else {
        print!("{}", league.table());
        println!(
            "({:.1} min matches, {} matches in {:.1} s)",
            cfg.minutes,
            total,
            start.elapsed().as_secs_f64()
        );
    }
    Ok(())
}

/// Matches played so far on standard error: one line redrawn on a
/// terminal, a line every ten seconds in a log. Wall-clock time only shows
/// here; the results never depend on it.
struct Progress {
    total: usize,
    done: usize,
    show: bool,
    tty: bool,
    last_print: f64,
}

impl Progress {
    fn new(total: usize, show: bool) -> Progress {
        Progress {
            total,
            done: 0,
            show,
            tty: std::io::stderr().is_terminal(),
            last_print: 0.0,
        }
    }

    fn advance(&mut self, n: usize, pair: &str, start: Instant) {
        self.done += n;
        if !self.show {
            return;
        }
        let secs = start.elapsed().as_secs_f64();
        if !self.tty && secs - self.last_print < 10.0 && self.done < self.total {
            return;
        }
        self.last_print = secs;
        let frac = self.done as f64 / self.total.max(1) as f64;
        let filled = ((frac * 24.0).round() as usize).min(24);
        let left = if self.done > 0 {
            secs * (self.total - self.done) as f64 / self.done as f64
        } else {
            f64::NAN
        };
        let line = format!(
            "[{}{}] {}/{} matches, {pair}, {:.0} s left",
            "#".repeat(filled),
            " ".repeat(24 - filled),
            self.done,
            self.total,
            left
        );
        let mut err = std::io::stderr();
        if self.tty {
            let _ = write!(err, "\r{line}\x1b[K");
        } else {
            let _ = writeln!(err, "{line}");
        }
    }

    fn finish(&self) {
        if self.show && self.tty {
            eprintln!();
        }
    }
}
