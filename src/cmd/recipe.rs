//! `naosoccer train --recipe FILE`: every stage of a training recipe in one
//! invocation, resumable at any point, with the wall-clock time of the whole
//! chain written into the run directory.
//!
//! A recipe is a TOML file (assets/recipes/): an optional `description` and
//! one `[[stage]]` table per stage. A stage's `name` names its directory;
//! every other key is a `train` option without its dashes (`steps`,
//! `pass-action`, `opponent`, ...), so a stage is exactly the `train` command
//! it stands for. `init-from = "previous"` starts a stage from the stage
//! before's final weights; no stage may start from anything else (a recipe
//! trains from scratch). The command sets `--out` and `--seed` itself.
//!
//! The run directory `DIR` gets `recipe.toml` (the recipe, as run),
//! `recipe-run.json` (the seed), one directory per stage (`01-NAME`, ...:
//! each an ordinary `train` run directory), `time.json` (wall-clock seconds
//! per stage and in total, summed over every sitting, rewritten every few
//! seconds) and, once the last stage is done, its `config.json` and
//! `final.safetensors`, so that `ppo:DIR` plays the recipe's team.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{bail, ensure, Context};
use clap::Parser;
use serde::{Deserialize, Serialize};

use super::learn::{run_train, TrainArgs};

/// Options the command sets for every stage: a recipe may not.
const SET_BY_COMMAND: [&str; 4] = ["out", "seed", "resume", "recipe"];

/// One stage: its name and the `train` arguments it stands for.
#[derive(Debug, Clone, PartialEq)]
pub struct Stage {
    pub name: String,
    /// `--key value` pairs and bare `--flag`s, in the file's order.
    pub args: Vec<String>,
    /// `init-from = "previous"`.
    pub from_previous: bool,
}

#[derive(Debug, Clone, PartialEq)]
pub struct Recipe {
    pub description: String,
    pub stages: Vec<Stage>,
}

/// `train`'s command line, parsed from a stage's arguments.
#[derive(Parser, Debug)]
#[command(name = "train", no_binary_name = true)]
struct StageCommand {
    #[command(flatten)]
    args: TrainArgs,
}

impl Recipe {
    /// Parses and checks a recipe: every stage must be a valid `train`
    /// command (checked here, before anything is trained).
    pub fn parse(text: &str, origin: &str) -> anyhow::Result<Recipe> {
        let table: toml::Table =
            toml::from_str(text).with_context(|| format!("recipe {origin}: not valid TOML"))?;
        let mut description = String::new();
        let mut stages = Vec::new();
        for (key, value) in &table {
            match key.as_str() {
                "description" => {
                    description = value
                        .as_str()
                        .with_context(|| {
                            format!("recipe {origin}: `description` must be a string")
                        })?
                        .to_string();
                }
                "stage" => {
                    let list = value.as_array().with_context(|| {
                        format!("recipe {origin}: `stage` must be an array of tables ([[stage]])")
                    })?;
                    for (i, s) in list.iter().enumerate() {
                        let t = s.as_table().with_context(|| {
                            format!("recipe {origin}: stage {} is not a table", i + 1)
                        })?;
                        stages.push(Stage::parse(t, i, origin)?);
                    }
                }
                other => bail!(
                    "recipe {origin}: unknown field `{other}` (a recipe has `description` and \
                     [[stage]] tables)"
                ),
            }
        }
        ensure!(!stages.is_empty(), "recipe {origin}: no [[stage]]");
        for (i, s) in stages.iter().enumerate() {
            if stages[..i].iter().any(|t| t.name == s.name) {
                bail!(
                    "recipe {origin}: stage {} has the same name as an earlier one ({:?})",
                    i + 1,
                    s.name
                );
            }
        }
        ensure!(
            !stages[0].from_previous,
            "recipe {origin}: stage 1 ({:?}) has init-from = \"previous\" but no stage comes before it",
            stages[0].name
        );
        let recipe = Recipe {
            description,
            stages,
        };
        // Every stage as the command it will be (placeholder directories).
        for (i, _) in recipe.stages.iter().enumerate() {
            let argv = recipe.stage_argv(i, Path::new("DIR"), 0);
            StageCommand::try_parse_from(&argv).map_err(|e| {
                anyhow::anyhow!(
                    "recipe {origin}, stage {} ({:?}): {}",
                    i + 1,
                    recipe.stages[i].name,
                    e.render().to_string().trim_end()
                )
            })?;
        }
        Ok(recipe)
    }

    /// The directory of stage `i` inside the run directory.
    pub fn stage_dir(&self, dir: &Path, i: usize) -> PathBuf {
        dir.join(format!("{:02}-{}", i + 1, self.stages[i].name))
    }

    /// Stage `i`'s `train` arguments in run directory `dir` with `seed`.
    fn stage_argv(&self, i: usize, dir: &Path, seed: u64) -> Vec<String> {
        let s = &self.stages[i];
        let mut argv = s.args.clone();
        if s.from_previous {
            argv.push("--init-from".into());
            argv.push(self.stage_dir(dir, i - 1).display().to_string());
        }
        argv.extend([
            "--seed".into(),
            seed.to_string(),
            "--out".into(),
            self.stage_dir(dir, i).display().to_string(),
        ]);
        argv
    }
}

impl Stage {
    fn parse(t: &toml::Table, i: usize, origin: &str) -> anyhow::Result<Stage> {
        let at = |k: &str| format!("recipe {origin}, stage {}, field `{k}`", i + 1);
        let name = t
            .get("name")
            .with_context(|| format!("recipe {origin}, stage {}: no `name`", i + 1))?
            .as_str()
            .with_context(|| format!("{}: must be a string", at("name")))?
            .to_string();
        ensure!(
            !name.is_empty()
                && name
                    .chars()
                    .all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '-'),
            "{}: {name:?} must be lower-case letters, digits and '-' (it names a directory)",
            at("name")
        );
        let mut args = Vec::new();
        let mut from_previous = false;
        for (key, value) in t {
            if key == "name" {
                continue;
            }
            ensure!(
                !SET_BY_COMMAND.contains(&key.as_str()),
                "{}: the command sets it (`train --recipe FILE --out DIR --seed N`)",
                at(key)
            );
            ensure!(
                !key.contains('_'),
                "{}: options are written as on the command line, with '-' (e.g. `pass-action`)",
                at(key)
            );
            if key == "init-from" {
                ensure!(
                    value.as_str() == Some("previous"),
                    "{}: a recipe trains from scratch; the only starting point is \"previous\" \
                     (the stage before's final weights)",
                    at(key)
                );
                from_previous = true;
                continue;
            }
            let flag = format!("--{key}");
            match value {
                toml::Value::Boolean(true) => args.push(flag),
                toml::Value::Boolean(false) => {}
                toml::Value::String(s) => args.extend([flag, s.clone()]),
                toml::Value::Integer(n) => args.extend([flag, n.to_string()]),
                toml::Value::Float(x) => args.extend([flag, x.to_string()]),
                // A list: the option once per entry (e.g. `scenarios`).
                toml::Value::Array(items) => {
                    for item in items {
                        let toml::Value::String(s) = item else {
                            bail!("{}: a list holds strings", at(key));
                        };
                        args.extend([flag.clone(), s.clone()]);
                    }
                }
                _ => bail!(
                    "{}: must be a string, a number, a boolean or a list of strings",
                    at(key)
                ),
            }
        }
        Ok(Stage {
            name,
            args,
            from_previous,
        })
    }
}

/// `recipe-run.json`: what the command line gave.
#[derive(Serialize, Deserialize)]
struct RunInfo {
    seed: u64,
}

/// `time.json`: wall-clock seconds per stage, summed over sittings.
#[derive(Serialize, Deserialize, Default)]
struct Times {
    /// Seconds of the whole chain so far.
    total_seconds: f64,
    stages: Vec<StageTime>,
    /// How many times the command ran on this directory.
    sittings: u32,
    /// Logical CPUs of the machine of the last sitting.
    cpus: usize,
    /// Each sitting's CPU model, in order: libtorch's kernels round by
    /// CPU, so a run resumed on another kind of machine goes on
    /// differently from one that was not stopped.
    #[serde(default)]
    cpu_models: Vec<String>,
}

#[derive(Serialize, Deserialize, Default, Clone)]
struct StageTime {
    name: String,
    seconds: f64,
    done: bool,
}

impl Times {
    fn load(dir: &Path, recipe: &Recipe) -> anyhow::Result<Times> {
        let path = dir.join("time.json");
        let mut t: Times = match std::fs::read_to_string(&path) {
            Ok(text) => serde_json::from_str(&text)
                .with_context(|| format!("{}: not a recipe's time file", path.display()))?,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => Times::default(),
            Err(e) => return Err(e).with_context(|| format!("reading {}", path.display())),
        };
        t.stages
            .resize_with(recipe.stages.len(), StageTime::default);
        for (s, r) in t.stages.iter_mut().zip(&recipe.stages) {
            s.name.clone_from(&r.name);
        }
        t.cpus = std::thread::available_parallelism().map_or(1, |n| n.get());
        t.cpu_models.push(cpu_model());
        Ok(t)
    }

    fn save(&mut self, dir: &Path) -> anyhow::Result<()> {
        self.total_seconds = self.stages.iter().map(|s| s.seconds).sum();
        let path = dir.join("time.json");
        let tmp = dir.join("time.json.tmp");
        std::fs::write(&tmp, serde_json::to_string_pretty(self)? + "\n")
            .with_context(|| format!("writing {}", tmp.display()))?;
        std::fs::rename(&tmp, &path).with_context(|| format!("writing {}", path.display()))
    }
}

/// The CPU's model name (Linux: /proc/cpuinfo), else its architecture.
fn cpu_model() -> String {
    std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|text| {
            text.lines()
                .find_map(|l| l.strip_prefix("model name")?.split_once(':'))
                .map(|(_, m)| m.trim().to_string())
        })
        .filter(|m| !m.is_empty())
        .unwrap_or_else(|| std::env::consts::ARCH.to_string())
}

/// `train --recipe FILE --out DIR --seed N`: a new recipe run.
pub fn start(
    recipe_path: &Path,
    out: &Path,
    seed: u64,
    threads: Option<usize>,
) -> anyhow::Result<()> {
    let text = std::fs::read_to_string(recipe_path)
        .with_context(|| format!("reading recipe {}", recipe_path.display()))?;
    Recipe::parse(&text, &recipe_path.display().to_string())?;
    ensure!(
        !out.join("recipe.toml").exists(),
        "{} already holds a recipe run: continue it with `naosoccer train --resume {}`, or \
         choose another --out",
        out.display(),
        out.display()
    );
    std::fs::create_dir_all(out).with_context(|| format!("creating {}", out.display()))?;
    std::fs::write(
        out.join("recipe-run.json"),
        serde_json::to_string_pretty(&RunInfo { seed })? + "\n",
    )?;
    // Written last: its presence marks a recipe run.
    std::fs::write(out.join("recipe.toml"), &text)?;
    run(out, threads)
}

/// Whether `dir` is a recipe run (`train --resume` continues it).
pub fn is_recipe_run(dir: &Path) -> bool {
    dir.join("recipe.toml").is_file()
}

/// Runs (or continues) every stage of the recipe run in `dir`: finished
/// stages are skipped, a stopped one continues from its latest checkpoint
/// (PPO team preset; other stages start over), the rest start afresh.
/// `threads`, if given, steps every stage's matches this sitting in place
/// of the recipe's `threads` (which changes nothing the stages learn).
pub fn run(dir: &Path, threads: Option<usize>) -> anyhow::Result<()> {
    let recipe_path = dir.join("recipe.toml");
    let text = std::fs::read_to_string(&recipe_path)
        .with_context(|| format!("reading {}", recipe_path.display()))?;
    let recipe = Recipe::parse(&text, &recipe_path.display().to_string())?;
    let info_path = dir.join("recipe-run.json");
    let info: RunInfo = serde_json::from_str(
        &std::fs::read_to_string(&info_path)
            .with_context(|| format!("reading {}", info_path.display()))?,
    )
    .with_context(|| format!("{}: not a recipe run's file", info_path.display()))?;
    let mut times = Times::load(dir, &recipe)?;
    times.sittings += 1;
    times.save(dir)?;
    let n = recipe.stages.len();
    for i in 0..n {
        let sdir = recipe.stage_dir(dir, i);
        let name = &recipe.stages[i].name;
        if sdir.join("final.safetensors").is_file() {
            eprintln!("stage {}/{n} {name}: done", i + 1);
            times.stages[i].done = true;
            continue;
        }
        let resumable = has_checkpoint(&sdir) && continues_from_checkpoint(&sdir);
        let argv = if resumable {
            eprintln!(
                "stage {}/{n} {name}: continuing from its latest checkpoint",
                i + 1
            );
            vec!["--resume".to_string(), sdir.display().to_string()]
        } else if has_checkpoint(&sdir) {
            eprintln!(
                "stage {}/{n} {name}: starting over (only decision-level PPO stages continue \
                 from a checkpoint)",
                i + 1
            );
            recipe.stage_argv(i, dir, info.seed)
        } else {
            eprintln!("stage {}/{n} {name}: starting", i + 1);
            recipe.stage_argv(i, dir, info.seed)
        };
        let argv = with_threads(argv, threads);
        let cmd = StageCommand::try_parse_from(&argv)
            .map_err(|e| anyhow::anyhow!("stage {}: {}", i + 1, e.render()))?;
        let base = times.stages[i].seconds;
        let started = Instant::now();
        let mut last_save = 0.0f64;
        let mut save_err = None;
        let label = format!("stage {}/{n} {name}", i + 1);
        run_train(cmd.args, Some(&label), &mut || {
            let secs = started.elapsed().as_secs_f64();
            if secs - last_save >= 10.0 {
                last_save = secs;
                times.stages[i].seconds = base + secs;
                if let Err(e) = times.save(dir) {
                    save_err.get_or_insert(e);
                }
            }
        })
        .with_context(|| format!("stage {}/{n} {name}", i + 1))?;
        if let Some(e) = save_err {
            return Err(e);
        }
        times.stages[i].seconds = base + started.elapsed().as_secs_f64();
        times.stages[i].done = true;
        times.save(dir)?;
    }
    let last = recipe.stage_dir(dir, n - 1);
    for f in ["config.json", "final.safetensors"] {
        std::fs::copy(last.join(f), dir.join(f))
            .with_context(|| format!("copying {} into {}", f, dir.display()))?;
    }
    // The team's spec names its algorithm (the last stage's config.json).
    let algo = std::fs::read_to_string(dir.join("config.json"))
        .ok()
        .and_then(|t| serde_json::from_str::<serde_json::Value>(&t).ok())
        .and_then(|c| c["algo"].as_str().map(str::to_string))
        .unwrap_or_else(|| "ppo".into());
    eprintln!(
        "recipe done in {:.1} min of wall clock over {} sitting(s) (time.json); the team: {algo}:{}",
        times.total_seconds / 60.0,
        times.sittings,
        dir.display()
    );
    Ok(())
}

/// `argv` with its `--threads` replaced by `threads`, if given.
fn with_threads(mut argv: Vec<String>, threads: Option<usize>) -> Vec<String> {
    if let Some(t) = threads {
        if let Some(at) = argv.iter().position(|a| a == "--threads") {
            argv.drain(at..(at + 2).min(argv.len()));
        }
        argv.extend(["--threads".into(), t.to_string()]);
    }
    argv
}

/// Whether the stage run in `dir` is one `train --resume` continues: its
/// config.json says decision-level PPO (`algo` "ppo" with a `ppo.decision`
/// table). Other sections of the file, such as `dqn.decision`, may be null.
fn continues_from_checkpoint(dir: &Path) -> bool {
    let Ok(text) = std::fs::read_to_string(dir.join("config.json")) else {
        return false;
    };
    let Ok(cfg) = serde_json::from_str::<serde_json::Value>(&text) else {
        return false;
    };
    cfg["algo"] == "ppo" && cfg["ppo"]["decision"].is_object()
}

fn has_checkpoint(dir: &Path) -> bool {
    std::fs::read_dir(dir.join("checkpoints")).is_ok_and(|rd| {
        rd.flatten()
            .any(|e| e.file_name().to_string_lossy().ends_with(".resume.json"))
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    const GOOD: &str = r#"
description = "two stages"
[[stage]]
name = "first"
algo = "ppo"
preset = "team"
steps = 20000
pass-action = true
no-shoot-mask = false
[[stage]]
name = "second"
algo = "ppo"
preset = "team"
init-from = "previous"
lr = 0.0001
"#;

    #[test]
    fn a_recipe_is_its_stages_train_commands() {
        let r = Recipe::parse(GOOD, "test").unwrap();
        assert_eq!(r.description, "two stages");
        assert_eq!(r.stages.len(), 2);
        let argv = r.stage_argv(1, Path::new("runs/x"), 7);
        let first = r.stage_argv(0, Path::new("runs/x"), 7);
        assert!(first.contains(&"--pass-action".to_string()), "{first:?}");
        assert!(!first.iter().any(|a| a == "--no-shoot-mask"), "{first:?}");
        let from = argv.iter().position(|a| a == "--init-from").unwrap();
        assert_eq!(
            Path::new(&argv[from + 1]),
            Path::new("runs/x").join("01-first")
        );
        assert!(argv.windows(2).any(|w| w[0] == "--seed" && w[1] == "7"));
        assert!(argv.windows(2).any(|w| w[0] == "--lr" && w[1] == "0.0001"));
    }

    #[test]
    fn bad_recipes_are_refused_naming_the_field() {
        let cases = [
            ("[[stage]]\nalgo = \"ppo\"\n", "no `name`"),
            ("[[stage]]\nname = \"a\"\nalgo = \"ppo\"\nout = \"x\"\n", "`out`"),
            (
                "[[stage]]\nname = \"a\"\nalgo = \"ppo\"\ninit-from = \"assets/policies/ppo-team-seed1\"\n",
                "from scratch",
            ),
            ("[[stage]]\nname = \"a\"\nalgo = \"ppo\"\ninit-from = \"previous\"\n", "stage 1"),
            ("[[stage]]\nname = \"a\"\nalgo = \"ppo\"\nbogus = 3\n", "--bogus"),
            ("[[stage]]\nname = \"a\"\nalgo = \"ppo\"\npass_action = true\n", "`pass_action`"),
            ("[[stage]]\nname = \"A b\"\nalgo = \"ppo\"\n", "`name`"),
            ("[[stage]]\nname = \"a\"\nalgo = \"ppo\"\n[[stage]]\nname = \"a\"\nalgo = \"ppo\"\n", "same name"),
            ("stages = 1\n", "unknown field `stages`"),
            ("description = \"x\"\n", "no [[stage]]"),
            ("[[stage]]\nname = \"a\"\nalgo = \"ppo\"\nsteps = [1]\n", "`steps`"),
        ];
        for (text, want) in cases {
            let err = format!("{:#}", Recipe::parse(text, "r.toml").unwrap_err());
            assert!(err.contains(want), "{text:?}: {err}");
            assert!(err.contains("r.toml"), "{err}");
        }
    }

    #[test]
    fn the_shipped_recipes_parse() {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/recipes");
        let mut n = 0;
        for e in std::fs::read_dir(&dir).unwrap() {
            let path = e.unwrap().path();
            if path.extension().is_some_and(|x| x == "toml") {
                let text = std::fs::read_to_string(&path).unwrap();
                Recipe::parse(&text, &path.display().to_string()).unwrap();
                n += 1;
            }
        }
        assert!(n > 0, "no recipes in {}", dir.display());
    }
}
