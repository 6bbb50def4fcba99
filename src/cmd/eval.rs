//! `naosoccer eval`: many matches between two teams, built-in or trained
//! (through `naosoccer-policy`, no libtorch). Wall-clock time is measured
//! here, at the edge; the results never depend on it.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::Context;
use clap::Args;
use naosoccer_policy::eval::{
    format_table, play_matches, summarise, Estimate, EvalPlan, Rate, Record, SeedScheme, Side,
    TeamSummary,
};
use naosoccer_referee::MatchConfig;

/// The match configuration: a TOML file or the defaults (assets/match.toml),
/// optionally with another match length.
pub fn match_config(path: Option<&PathBuf>, minutes: Option<f32>) -> anyhow::Result<MatchConfig> {
    let mut cfg = match path {
        Some(p) => MatchConfig::from_file(p).with_context(|| format!("reading {}", p.display()))?,
        None => MatchConfig::default(),
    };
    if let Some(m) = minutes {
        anyhow::ensure!(m > 0.0, "--minutes must be positive, got {m}");
        cfg.minutes = m;
    }
    Ok(cfg)
}

#[derive(Args, Debug)]
#[command(after_help = "Examples:
  naosoccer eval --blue ppo:runs/ppo-1 --red scripted --matches 100 --both-sides --seed 1
  naosoccer eval --blue ppo:assets/policies/ppo-paper-seed1 --red dqn:assets/policies/dqn-seed1
  naosoccer eval --blue ppo:runs/ppo-1 --red scripted:assets/scripted/press.toml --both-sides

Match i has a seed derived from --seed and i, so two evaluations with the
same --seed play the same matches. Evaluation seeds have their own
derivation, with the top bit set, and training seeds have it clear: an
evaluation never plays a match a training run played, whatever the seeds
(--legacy-seeds replays evaluations made before that rule).

With --both-sides the odd-numbered matches swap the sides (the --blue team
plays red); the table and the JSON still report each team under its own
name, with its record as blue and as red. Prints average goals, ball-control
rate, passes, shots (mean ± 95% CI over matches), wins/draws/losses and the
win rate with its Wilson 95% interval per team.

A PPO team (ppo:DIR) samples its actions from its policy, drawing from a hash
of the match seed, robot and tick; ppo-greedy:DIR takes the most likely action;
dqn:DIR takes the largest Q-value; dqn-epsilon:DIR acts epsilon-greedily with
its training run's epsilon.")]
pub struct EvalArgs {
    /// First team (blue, unless --both-sides swaps it): scripted,
    /// scripted:KEY=VAL,..., scripted:FILE.toml, random, idle, ppo:DIR,
    /// ppo-greedy:DIR, dqn:DIR or dqn-epsilon:DIR.
    #[arg(long)]
    blue: String,
    /// Second team: as --blue.
    #[arg(long, default_value = "scripted")]
    red: String,
    /// Matches to play.
    #[arg(long, default_value_t = 50)]
    matches: usize,
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Play every other match with the sides swapped.
    #[arg(long)]
    both_sides: bool,
    /// Seed match i as evaluations did before evaluation and training seeds
    /// were separated (the seed of training match i's first episode), to
    /// replay an old eval.json.
    #[arg(long)]
    legacy_seeds: bool,
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
}

pub fn eval_cmd(a: EvalArgs) -> anyhow::Result<()> {
    anyhow::ensure!(a.matches > 0, "--matches must be at least 1");
    let cfg = match_config(a.config.as_ref(), a.minutes)?;
    let mut blue = Side::parse(&a.blue)?;
    let mut red = Side::parse(&a.red)?;
    let plan = EvalPlan {
        matches: a.matches,
        seed: a.seed,
        both_sides: a.both_sides,
        seeds: if a.legacy_seeds {
            SeedScheme::Legacy
        } else {
            SeedScheme::Eval
        },
    };
    let start = Instant::now();
    let results = play_matches(&cfg, &mut blue, &mut red, &plan, a.threads)?;
    let secs = start.elapsed().as_secs_f64();
    let rows = summarise(&results, &a.blue, &a.red);
    if a.json {
        let est = |e: &Estimate| serde_json::json!({"mean": e.mean, "ci95": e.ci95});
        let rate = |r: &Rate| serde_json::json!({"rate": r.rate, "low": r.low, "high": r.high});
        let rec =
            |r: &Record| serde_json::json!({"wins": r.wins, "draws": r.draws, "losses": r.losses});
        let team = |r: &TeamSummary| {
            serde_json::json!({
                "name": r.name, "goals": est(&r.goals), "control_rate_percent": est(&r.control_rate),
                "passes": est(&r.passes), "shots": est(&r.shots),
                "wins": r.wins, "draws": r.draws, "losses": r.losses,
                "win_rate": rate(&r.win_rate), "as_blue": rec(&r.as_blue), "as_red": rec(&r.as_red),
            })
        };
        // Per match, the --blue team's goals first, whichever colour it played.
        let scores: Vec<_> = results
            .iter()
            .map(|r| [r.goals_of(true), r.goals_of(false)])
            .collect();
        let swapped: Vec<_> = results.iter().map(|r| r.swapped).collect();
        println!(
            "{}",
            serde_json::json!({
                "matches": a.matches, "seed": a.seed, "minutes": cfg.minutes,
                "both_sides": a.both_sides, "seed_scheme": plan.seeds.name(),
                "blue": team(&rows[0]), "red": team(&rows[1]), "scores": scores,
                "swapped": swapped, "wall_seconds": secs,
            })
        );
    } else {
        print!("{}", format_table(&rows, a.matches));
        println!("({:.1} min matches, {:.1} s)", cfg.minutes, secs);
    }
    Ok(())
}
