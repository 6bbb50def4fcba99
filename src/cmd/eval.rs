//! `naosoccer eval`: many matches between two teams, built-in or trained
//! (through `naosoccer-eval`, no libtorch). Wall-clock time is measured
//! here, at the edge; the results never depend on it.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::Context;
use clap::Args;
use naosoccer::interrupt;
use naosoccer_eval::eval::{play_matches_until, EvalPlan, EvalReport, SeedScheme, Side};
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
  naosoccer eval --blue scripted --red random --matches 4 --first-match 0 --json > a.json
  naosoccer eval --blue scripted --red random --matches 4 --first-match 4 --json > b.json
  naosoccer eval --merge a.json b.json        # = --matches 8, as one run

Match i has a seed derived from --seed and i, so two evaluations with the
same --seed play the same matches. Evaluation seeds have their own
derivation, with the top bit set, and training seeds have it clear: an
evaluation never plays a match a training run played, whatever the seeds
(--legacy-seeds replays evaluations made before that rule).

With --both-sides the odd-numbered matches swap the sides (the --blue team
plays red); the table and the JSON still report each team under its own
name, with its record as blue and as red. Prints average goals, ball-control
rate, passes, aimed passes (whose kick was the action pass swung toward a
receiver, not a shot a teammate happened to reach), passes of 1 m or more
(from the kick to where the receiver took control; most passes are shorter,
a kick into a teammate at the ball), shots
(mean ± 95% CI over matches), wins/draws/losses and the win rate with its
Wilson 95% interval per team.

Blocks: --first-match I --matches N plays matches I to I+N-1 of the
evaluation (the same seeds and sides as in one run of I+N matches), and
reports them alone. --json lists every match in \"results\": its global
index, seed, whether it was swapped, both teams' goals, ball control,
passes, aimed_passes, long_passes (1 m or more) and shots (the --blue team first) and its final state hash, with
\"first_match\" and \"config_hash\" (a hash of the match configuration).
--merge FILE.json... reads such --json outputs of one evaluation (same
teams, seed, seed scheme, --both-sides, match length and configuration) and
prints exactly what one run over all their matches prints, the table or
with --json the object; its wall_seconds is the sum of the files'. It
refuses files of different evaluations, a match in two files, and gaps.

A PPO team (ppo:DIR) samples its actions from its policy, drawing from a hash
of the match seed, robot and tick; ppo-greedy:DIR takes the most likely action;
dqn:DIR takes the largest Q-value; dqn-epsilon:DIR acts epsilon-greedily with
its training run's epsilon.")]
pub struct EvalArgs {
    /// First team (blue, unless --both-sides swaps it): scripted,
    /// scripted:KEY=VAL,..., scripted:FILE.toml, random, idle, ppo:DIR,
    /// ppo-greedy:DIR, dqn:DIR or dqn-epsilon:DIR.
    #[arg(long, required_unless_present = "merge")]
    blue: Option<String>,
    /// Second team: as --blue [default: scripted; with --scenario, the
    /// scenario's `opponent`].
    #[arg(long)]
    red: Option<String>,
    /// Matches to play.
    #[arg(long, default_value_t = 50)]
    matches: usize,
    /// The global index of the first match played: plays matches
    /// FIRST_MATCH .. FIRST_MATCH+MATCHES-1 of the evaluation, seeded and
    /// swapped as in one run of all of them.
    #[arg(long, default_value_t = 0)]
    first_match: usize,
    /// The evaluation's seed: match i's seed is derived from it and i, so
    /// the same --seed plays the same matches (see below).
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
    /// Play a scenario (docs/SCENARIOS.md) instead of whole matches: start
    /// i has match i's seed, the --blue team is the team under test (the
    /// file's own team), playing blue in the even starts and red in the odd
    /// ones, and --red the opponents. Prints the success rate with its
    /// Wilson 95% interval, the mean time to a success and how many starts
    /// each end condition ended: the row `academy` prints for a drill
    /// (with --json, academy's object with one drill).
    #[arg(
        long,
        value_name = "FILE",
        conflicts_with_all = ["first_match", "both_sides", "legacy_seeds", "minutes"]
    )]
    scenario: Option<PathBuf>,
    /// Play nothing: merge these --json outputs of blocks of one evaluation
    /// and print what one run over all their matches prints.
    #[arg(
        long,
        num_args = 1..,
        value_name = "FILE.json",
        conflicts_with_all = [
            "blue", "red", "matches", "first_match", "seed", "both_sides",
            "legacy_seeds", "config", "minutes", "threads", "scenario",
        ]
    )]
    merge: Vec<PathBuf>,
}

pub fn eval_cmd(a: EvalArgs) -> anyhow::Result<()> {
    if let Some(path) = &a.scenario {
        return scenario(&a, path);
    }
    let (report, interrupted) = if a.merge.is_empty() {
        play(&a)?
    } else {
        (Some(merge(&a.merge)?), false)
    };
    if let Some(report) = &report {
        if a.json {
            println!("{}", report.to_json());
        } else {
            print!("{}", report.table());
        }
    }
    if interrupted {
        let played = report.as_ref().map_or(0, |r| r.plan.matches);
        return Err(interrupt::Interrupted::new(format!(
            "eval stopped after {played} of {} matches{}",
            a.matches,
            if played > 0 {
                " (the results above are of those: what --matches with that number prints)"
            } else {
                ""
            }
        ))
        .into());
    }
    Ok(())
}

/// Matches are played in blocks of this many, so that Ctrl-C keeps every
/// block already finished (a block's results are what one run over all
/// matches gives for them: see --first-match).
const BLOCK: usize = 8;

/// The report of the matches played (`None` if stopped before the first
/// block ended) and whether Ctrl-C stopped the evaluation early.
fn play(a: &EvalArgs) -> anyhow::Result<(Option<EvalReport>, bool)> {
    anyhow::ensure!(a.matches > 0, "--matches must be at least 1");
    anyhow::ensure!(
        a.first_match.checked_add(a.matches).is_some(),
        "--first-match {} plus --matches {} is out of range",
        a.first_match,
        a.matches
    );
    let blue_spec = a.blue.clone().context("--blue is required")?;
    let cfg = match_config(a.config.as_ref(), a.minutes)?;
    let mut blue = Side::parse(&blue_spec)?;
    let red_spec = a.red.clone().unwrap_or_else(|| "scripted".to_owned());
    let mut red = Side::parse(&red_spec)?;
    let plan = EvalPlan {
        matches: a.matches,
        first_match: a.first_match,
        seed: a.seed,
        both_sides: a.both_sides,
        seeds: if a.legacy_seeds {
            SeedScheme::Legacy
        } else {
            SeedScheme::Eval
        },
    };
    interrupt::watch()?;
    let start = Instant::now();
    let mut results = Vec::with_capacity(plan.matches);
    let mut stopped = false;
    while results.len() < plan.matches {
        let block = EvalPlan {
            matches: BLOCK.min(plan.matches - results.len()),
            first_match: plan.first_match + results.len(),
            ..plan
        };
        match play_matches_until(
            &cfg,
            &mut blue,
            &mut red,
            &block,
            a.threads,
            &interrupt::interrupted,
        )? {
            Some(r) => results.extend(r),
            None => {
                stopped = true;
                break;
            }
        }
    }
    let secs = start.elapsed().as_secs_f64();
    if results.is_empty() {
        return Ok((None, stopped));
    }
    let played = EvalPlan {
        matches: results.len(),
        ..plan
    };
    let report = EvalReport::new([blue_spec, red_spec], played, &cfg, &results, secs);
    Ok((Some(report), stopped))
}

/// The reports in `files`, merged into one run's.
fn merge(files: &[PathBuf]) -> anyhow::Result<EvalReport> {
    let mut parts = Vec::with_capacity(files.len());
    for f in files {
        let text =
            std::fs::read_to_string(f).with_context(|| format!("reading {}", f.display()))?;
        let label = f.display().to_string();
        let value: serde_json::Value = serde_json::from_str(&text)
            .with_context(|| format!("{label}: not JSON (an `eval --json` output?)"))?;
        parts.push((label.clone(), EvalReport::from_json(&label, &value)?));
    }
    Ok(EvalReport::merge(&parts)?)
}

/// `--scenario`: the starts of one drill, as `academy` plays them.
fn scenario(a: &EvalArgs, path: &std::path::Path) -> anyhow::Result<()> {
    use naosoccer_eval::academy::{self, DrillPlan};
    anyhow::ensure!(a.matches > 0, "--matches must be at least 1");
    let blue = a.blue.clone().context("--blue is required")?;
    let cfg = match_config(a.config.as_ref(), None)?;
    let s = naosoccer_referee::Scenario::from_file(path)?;
    s.check(&cfg)
        .with_context(|| format!("{} against the match configuration", path.display()))?;
    let plan = DrillPlan {
        starts: a.matches,
        seed: a.seed,
    };
    interrupt::watch()?;
    let start = Instant::now();
    let Some(row) = super::academy::play(&cfg, &s, &blue, a.red.as_deref(), &plan, a.threads)?
    else {
        return Err(
            interrupt::Interrupted::new("eval stopped before the starts were played").into(),
        );
    };
    let wall = start.elapsed().as_secs_f64();
    let rows = [row];
    if a.json {
        println!(
            "{}",
            academy::to_json(&blue, a.matches, a.seed, &rows, wall)
        );
    } else {
        print!("{}", academy::format_table(&blue, a.matches, a.seed, &rows));
    }
    Ok(())
}
