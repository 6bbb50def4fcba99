//! `naosoccer academy`: every drill of the academy (or of a directory of
//! scenario files), many starts each, one table. The drills that ship are
//! built into the binary, so the command works from any directory.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::Context;
use clap::Args;
use naosoccer::interrupt;
use naosoccer_eval::academy::{self, DrillPlan, DrillReport};
use naosoccer_eval::eval::Side;
use naosoccer_referee::{MatchConfig, Scenario};

use super::eval::match_config;

macro_rules! drill {
    ($name:literal) => {
        (
            $name,
            include_str!(concat!("../../assets/scenarios/", $name, ".toml")),
        )
    };
}

/// The academy as it ships: assets/scenarios/, in the order of
/// docs/SCENARIOS.md's table.
pub const DRILLS: &[(&str, &str)] = &[
    drill!("empty-goal-close"),
    drill!("empty-goal"),
    drill!("run-to-score"),
    drill!("run-to-score-with-keeper"),
    drill!("pass-and-shoot-with-keeper"),
    drill!("run-pass-and-shoot-with-keeper"),
    drill!("3-vs-1-with-keeper"),
    drill!("corner"),
    drill!("counterattack-easy"),
    drill!("counterattack-hard"),
    drill!("single-goal-vs-lazy"),
    drill!("kick-in"),
    drill!("goal-kick-under-pressure"),
    drill!("1-vs-1-keeper"),
    drill!("defend-2-vs-1"),
];

#[derive(Args, Debug)]
#[command(after_help = "\
Plays every drill of the academy (docs/SCENARIOS.md lists them): --starts
starts each, start i with the seed of evaluation match i under --seed, the
team under test playing blue in the even starts and red in the odd ones.
Each drill's file says which policy the opponents play. A start ends at its
first end condition that holds, or when its time is up (a failure unless
the file says otherwise).

Prints one row per drill: the success rate in percent with its Wilson 95%
interval, the mean game time to a success (seconds), the opponents' policy
and how many starts each end condition ended. With --json, stdout holds one
object:
  {\"policy\", \"starts\", \"seed\", \"ticks\", \"wall_seconds\",
   \"drills\": [{\"drill\", \"opponent\", \"starts\", \"successes\", \"success_rate\",
     \"ci\": [lo, hi], \"mean_time_to_success\" (seconds or null),
     \"outcomes\": {NAME: {\"starts\", \"successes\"}}, \"ticks\"}, ...]}
The same --seed and --starts play the same starts: `eval --scenario FILE
--blue SPEC --matches N --seed S` plays a drill's N starts of
`academy --starts N --seed S`.

Examples:
  naosoccer academy --policy scripted
  naosoccer academy --policy ppo:assets/policies/ppo-team-seed1 --starts 50 --json
  naosoccer academy --policy scripted:3 --drill corner --drill kick-in
  naosoccer academy --policy scripted --dir my-drills/")]
pub struct AcademyArgs {
    /// The team under test: scripted, scripted:1..5, scripted:KEY=VAL,...,
    /// scripted:FILE.toml, random, idle, ppo:DIR, ppo-greedy:DIR, dqn:DIR
    /// or dqn-epsilon:DIR.
    #[arg(long, value_name = "SPEC")]
    policy: String,
    /// Starts of each drill.
    #[arg(long, default_value_t = 100, value_name = "N")]
    starts: usize,
    /// The academy's seed: start i of every drill has the seed of
    /// evaluation match i under it.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Play only these drills (a name from the table; repeat for more).
    #[arg(long, value_name = "NAME")]
    drill: Vec<String>,
    /// Play the scenario files (*.toml) of this directory, in file-name
    /// order, instead of the built-in academy.
    #[arg(long, value_name = "DIR")]
    dir: Option<PathBuf>,
    /// Match configuration (TOML); default: the built-in assets/match.toml.
    #[arg(long, value_name = "FILE")]
    config: Option<PathBuf>,
    /// Threads stepping starts.
    #[arg(long, default_value_t = 2, value_name = "T")]
    threads: usize,
    /// One JSON object instead of the table.
    #[arg(long)]
    json: bool,
}

/// The drills to play: the built-in academy or a directory's files.
fn drills(dir: Option<&Path>) -> anyhow::Result<Vec<Scenario>> {
    let Some(dir) = dir else {
        return DRILLS
            .iter()
            .map(|(name, text)| {
                Scenario::from_toml(text, Some(name))
                    .with_context(|| format!("built-in drill {name}"))
            })
            .collect();
    };
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
        .with_context(|| format!("reading {}", dir.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .collect();
    files.sort();
    anyhow::ensure!(
        !files.is_empty(),
        "{}: no scenario files (*.toml)",
        dir.display()
    );
    files
        .iter()
        .map(|p| Scenario::from_file(p).map_err(anyhow::Error::from))
        .collect()
}

pub fn academy_cmd(a: AcademyArgs) -> anyhow::Result<()> {
    anyhow::ensure!(a.starts > 0, "--starts must be at least 1");
    let cfg = match_config(a.config.as_ref(), None)?;
    let mut all = drills(a.dir.as_deref())?;
    for name in &a.drill {
        anyhow::ensure!(
            all.iter().any(|s| &s.name == name),
            "--drill {name}: no such drill (the drills: {})",
            all.iter()
                .map(|s| s.name.as_str())
                .collect::<Vec<_>>()
                .join(", ")
        );
    }
    if !a.drill.is_empty() {
        all.retain(|s| a.drill.contains(&s.name));
    }
    for s in &all {
        s.check(&cfg).with_context(|| format!("drill {}", s.name))?;
    }
    // A bad team spec fails before any drill is played.
    Side::parse(&a.policy).with_context(|| format!("--policy {}", a.policy))?;
    interrupt::watch()?;
    let start = Instant::now();
    let plan = DrillPlan {
        starts: a.starts,
        seed: a.seed,
    };
    let mut rows = Vec::with_capacity(all.len());
    for s in &all {
        match play(&cfg, s, &a.policy, None, &plan, a.threads)? {
            Some(row) => rows.push(row),
            None => {
                return Err(interrupt::Interrupted::new(format!(
                    "academy stopped during drill {} ({} of {} drills done)",
                    s.name,
                    rows.len(),
                    all.len()
                ))
                .into())
            }
        }
    }
    let wall = start.elapsed().as_secs_f64();
    if a.json {
        println!(
            "{}",
            academy::to_json(&a.policy, a.starts, a.seed, &rows, wall)
        );
    } else {
        print!(
            "{}",
            academy::format_table(&a.policy, a.starts, a.seed, &rows)
        );
    }
    Ok(())
}

/// Plays one drill: `policy` under test against `opponent` (the file's
/// when `None`). `None` if Ctrl-C stopped it.
pub fn play(
    cfg: &MatchConfig,
    scenario: &Scenario,
    policy: &str,
    opponent: Option<&str>,
    plan: &DrillPlan,
    threads: usize,
) -> anyhow::Result<Option<DrillReport>> {
    let opponent = opponent.unwrap_or(&scenario.opponent);
    // Fresh sides for every drill: a trained team keeps per-robot state by
    // match seed, and the drills share their seeds.
    let mut own = Side::parse(policy).with_context(|| format!("policy {policy}"))?;
    let mut other = Side::parse(opponent)
        .with_context(|| format!("drill {}: opponent {opponent}", scenario.name))?;
    let results = academy::play_drill(
        cfg,
        scenario,
        &mut own,
        &mut other,
        plan,
        threads,
        &interrupt::interrupted,
    )
    .with_context(|| format!("drill {}", scenario.name))?;
    Ok(results.map(|r| DrillReport::new(&scenario.name, policy, opponent, cfg, &r)))
}
