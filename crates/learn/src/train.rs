//! Training runs: the configuration saved beside the checkpoints, the loop
//! for each algorithm, and the metrics CSV.
//!
//! A run directory:
//! - `config.json`: this [`TrainConfig`] (networks, hyperparameters, match
//!   configuration, observation layout version and scale),
//! - `metrics.csv`: one row per update (PPO) or log interval (DQN),
//! - `checkpoints/step-N.safetensors` every `checkpoint_every` transitions,
//! - `final.safetensors` at the end.
//!
//! Nothing here reads the clock: the same configuration, seed and thread
//! count write the same metrics.

use std::io::Write;
use std::path::{Path, PathBuf};

use naosoccer_client::PolicyKind;
use naosoccer_referee::MatchConfig;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

use crate::dqn::{Dqn, DqnConfig, Held, NStep};
use crate::env::{EnvConfig, Episode, Opponent, VecEnv};
use crate::obs::{ObsScale, OBS_DIM, OBS_VERSION};
use crate::policy::{save_stores, ActMode, LearnedPolicy};
use crate::ppo::{Ppo, PpoConfig, Rollout};
use crate::LearnError;

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Algo {
    Dqn,
    Ppo,
}

impl std::fmt::Display for Algo {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Algo::Dqn => "dqn",
            Algo::Ppo => "ppo",
        })
    }
}

impl std::str::FromStr for Algo {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "dqn" => Ok(Algo::Dqn),
            "ppo" => Ok(Algo::Ppo),
            o => Err(format!("unknown algorithm {o:?} (expected dqn or ppo)")),
        }
    }
}

/// Who the learner plays against during training.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum OpponentSpec {
    /// A built-in policy by spec: `scripted`, `scripted:KEY=VAL,...`,
    /// `random`, `idle`.
    Builtin(String),
    /// A frozen trained team, `ppo:DIR` or `dqn:DIR`.
    Frozen(String),
    /// The learner's own snapshot, refreshed every `every` transitions.
    SelfPlay { every: u64 },
}

impl std::str::FromStr for OpponentSpec {
    type Err = String;
    /// `scripted` | `random` | `idle` | `ppo:DIR` | `dqn:DIR` | `self-play[:N]`.
    fn from_str(s: &str) -> Result<Self, String> {
        if let Some(rest) = s.strip_prefix("self-play") {
            let every = match rest.strip_prefix(':') {
                Some(n) => n
                    .parse()
                    .map_err(|_| format!("self-play:N needs a number of transitions, got {n:?}"))?,
                None if rest.is_empty() => 100_000,
                None => return Err(format!("unknown opponent {s:?}")),
            };
            return Ok(OpponentSpec::SelfPlay { every });
        }
        if s.starts_with("ppo:") || s.starts_with("dqn:") {
            return Ok(OpponentSpec::Frozen(s.to_string()));
        }
        // Saved as the spec that spells out a scripted variant's parameters,
        // so config.json does not depend on a TOML file staying as it was.
        let kind = s
            .parse::<PolicyKind>()
            .map_err(|e| format!("{e}; or ppo:DIR, dqn:DIR, self-play[:N]"))?;
        Ok(OpponentSpec::Builtin(kind.to_string()))
    }
}

/// Everything a training run depends on; saved as `config.json`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TrainConfig {
    pub algo: Algo,
    /// Robot transitions (one learning robot, one control tick) to train for.
    pub steps: u64,
    pub seed: u64,
    /// Matches played side by side.
    pub matches: usize,
    /// Threads that step matches (the networks use `tch::set_num_threads`).
    pub threads: usize,
    /// Players the network controls (all four by default).
    pub learners: Vec<usize>,
    /// The built-in policy of own players that do not learn.
    pub teammates: String,
    pub opponent: OpponentSpec,
    /// Transitions between checkpoints.
    pub checkpoint_every: u64,
    /// DQN: vectorised steps between metric rows.
    pub log_every: usize,
    pub ppo: PpoConfig,
    pub dqn: DqnConfig,
    #[serde(rename = "match")]
    pub match_config: MatchConfig,
    pub obs_version: u32,
    pub obs_scale: ObsScale,
}

impl TrainConfig {
    pub fn new(algo: Algo, match_config: MatchConfig) -> TrainConfig {
        TrainConfig {
            algo,
            steps: 1_000_000,
            seed: 0,
            matches: 16,
            threads: 2,
            learners: vec![0, 1, 2, 3],
            teammates: "idle".into(),
            opponent: OpponentSpec::Builtin("scripted".into()),
            checkpoint_every: 250_000,
            log_every: 128,
            ppo: PpoConfig::paper(),
            dqn: DqnConfig::default(),
            obs_version: OBS_VERSION,
            obs_scale: ObsScale::from_config(&match_config),
            match_config,
        }
    }
}

/// One row of `metrics.csv`.
#[derive(Debug, Clone, PartialEq)]
pub struct MetricsRow {
    pub update: u64,
    /// Control ticks per match so far (the figures' "timeslots").
    pub timeslot: u64,
    pub transitions: u64,
    pub episodes: u64,
    /// Mean reward per robot and tick over this row's interval, for the team
    /// and per learning robot.
    pub reward: f64,
    pub reward_per_robot: Vec<f64>,
    /// Mean over episodes that ended in this interval (NaN when none did).
    pub episode_return: f64,
    pub goals_for: f64,
    pub goals_against: f64,
    /// PPO: policy loss; DQN: TD loss.
    pub loss: f64,
    pub value_loss: f64,
    pub entropy: f64,
}

impl MetricsRow {
    pub fn header(robots: &[usize]) -> String {
        let mut h = String::from("update,timeslot,transitions,episodes,reward");
        for p in robots {
            h.push_str(&format!(",reward_p{p}"));
        }
        h.push_str(",episode_return,goals_for,goals_against,loss,value_loss,entropy");
        h
    }

    pub fn to_csv(&self) -> String {
        let mut s = format!(
            "{},{},{},{},{:.6}",
            self.update, self.timeslot, self.transitions, self.episodes, self.reward
        );
        for r in &self.reward_per_robot {
            s.push_str(&format!(",{r:.6}"));
        }
        s.push_str(&format!(
            ",{:.6},{:.4},{:.4},{:.6},{:.6},{:.6}",
            self.episode_return,
            self.goals_for,
            self.goals_against,
            self.loss,
            self.value_loss,
            self.entropy
        ));
        s
    }
}

/// What a run reports as it goes (the CLI adds wall-clock rates).
#[derive(Debug, Clone)]
pub struct Progress<'a> {
    pub row: &'a MetricsRow,
    pub total_steps: u64,
}

/// Accumulates rewards and finished episodes between metric rows.
struct Tally {
    robots: usize,
    reward_sum: Vec<f64>,
    samples: u64,
    episodes: Vec<Episode>,
    total_episodes: u64,
}

impl Tally {
    fn new(robots: usize) -> Tally {
        Tally {
            robots,
            reward_sum: vec![0.0; robots],
            samples: 0,
            episodes: Vec::new(),
            total_episodes: 0,
        }
    }

    fn add_rewards(&mut self, rewards: &[f32]) {
        for (i, r) in rewards.iter().enumerate() {
            self.reward_sum[i % self.robots] += f64::from(*r);
        }
        self.samples += (rewards.len() / self.robots) as u64;
    }

    fn row(
        &mut self,
        update: u64,
        timeslot: u64,
        transitions: u64,
        losses: (f64, f64, f64),
    ) -> MetricsRow {
        let per: Vec<f64> = self
            .reward_sum
            .iter()
            .map(|s| s / self.samples.max(1) as f64)
            .collect();
        let reward = per.iter().sum::<f64>() / per.len() as f64;
        let n = self.episodes.len();
        let mean = |f: &dyn Fn(&Episode) -> f64| {
            if n == 0 {
                f64::NAN
            } else {
                self.episodes.iter().map(f).sum::<f64>() / n as f64
            }
        };
        let episode_return = mean(&|e| {
            e.returns.iter().map(|&r| f64::from(r)).sum::<f64>() / e.returns.len() as f64
        });
        let goals_for = mean(&|e| f64::from(e.goals_for));
        let goals_against = mean(&|e| f64::from(e.goals_against));
        self.total_episodes += n as u64;
        let row = MetricsRow {
            update,
            timeslot,
            transitions,
            episodes: self.total_episodes,
            reward,
            reward_per_robot: per,
            episode_return,
            goals_for,
            goals_against,
            loss: losses.0,
            value_loss: losses.1,
            entropy: losses.2,
        };
        self.reward_sum.iter_mut().for_each(|s| *s = 0.0);
        self.samples = 0;
        self.episodes.clear();
        row
    }
}

/// Writes the run directory as training goes.
struct RunDir {
    dir: PathBuf,
    metrics: std::io::BufWriter<std::fs::File>,
}

impl RunDir {
    fn create(dir: &Path, cfg: &TrainConfig) -> Result<RunDir, LearnError> {
        std::fs::create_dir_all(dir.join("checkpoints")).map_err(|e| LearnError::io(dir, e))?;
        let cfg_path = dir.join("config.json");
        let json = serde_json::to_string_pretty(cfg).map_err(|e| LearnError::Json {
            path: cfg_path.clone(),
            source: e,
        })?;
        std::fs::write(&cfg_path, json).map_err(|e| LearnError::io(&cfg_path, e))?;
        let mpath = dir.join("metrics.csv");
        let f = std::fs::File::create(&mpath).map_err(|e| LearnError::io(&mpath, e))?;
        let mut metrics = std::io::BufWriter::new(f);
        writeln!(metrics, "{}", MetricsRow::header(&cfg.learners))
            .map_err(|e| LearnError::io(&mpath, e))?;
        Ok(RunDir {
            dir: dir.to_path_buf(),
            metrics,
        })
    }

    fn write_row(&mut self, row: &MetricsRow) -> Result<(), LearnError> {
        let p = self.dir.join("metrics.csv");
        writeln!(self.metrics, "{}", row.to_csv()).map_err(|e| LearnError::io(&p, e))?;
        self.metrics.flush().map_err(|e| LearnError::io(&p, e))
    }
}

/// What a finished run returns.
#[derive(Debug, Clone)]
pub struct TrainSummary {
    pub rows: Vec<MetricsRow>,
    pub transitions: u64,
    pub final_weights: PathBuf,
}

fn opponent_for(cfg: &TrainConfig) -> Result<Opponent, LearnError> {
    Ok(match &cfg.opponent {
        OpponentSpec::Builtin(name) => Opponent::Builtin(
            name.parse::<PolicyKind>()
                .map_err(|e| LearnError::Config(e.to_string()))?,
        ),
        OpponentSpec::Frozen(spec) => {
            let mut p = LearnedPolicy::load(spec)?;
            p.set_match_seed(cfg.seed);
            Opponent::Net(Box::new(p))
        }
        // The first snapshot is the untrained network, as in self-play from
        // scratch. It plays as the learner's team would (`ppo:` samples,
        // `dqn:` is greedy), with draws seeded by the run's seed.
        OpponentSpec::SelfPlay { .. } => {
            let mut p = LearnedPolicy::untrained(cfg, "self-play".into());
            p.set_mode(match cfg.algo {
                Algo::Ppo => ActMode::Sample,
                Algo::Dqn => ActMode::Greedy,
            });
            p.set_match_seed(cfg.seed);
            Opponent::Net(Box::new(p))
        }
    })
}

fn make_env(cfg: &TrainConfig) -> Result<VecEnv, LearnError> {
    if cfg.obs_version != OBS_VERSION {
        return Err(LearnError::Config(format!(
            "observation layout v{} requested, this build has v{OBS_VERSION}",
            cfg.obs_version
        )));
    }
    let teammates = cfg
        .teammates
        .parse::<PolicyKind>()
        .map_err(|e| LearnError::Config(e.to_string()))?;
    VecEnv::new(
        &cfg.match_config,
        EnvConfig {
            matches: cfg.matches,
            learners: cfg.learners.clone(),
            teammates,
            threads: cfg.threads,
            seed: cfg.seed,
        },
        opponent_for(cfg)?,
    )
}

/// Trains as `cfg` says, writing the run directory `out`. `progress` sees
/// every metrics row.
pub fn train(
    cfg: &TrainConfig,
    out: &Path,
    progress: &mut dyn FnMut(&Progress<'_>),
) -> Result<TrainSummary, LearnError> {
    tch::manual_seed(cfg.seed as i64);
    match cfg.algo {
        Algo::Ppo => train_ppo(cfg, out, progress),
        Algo::Dqn => train_dqn(cfg, out, progress),
    }
}

fn checkpoint_due(before: u64, after: u64, every: u64) -> bool {
    every > 0 && before / every != after / every
}

fn snapshot_due(cfg: &TrainConfig, before: u64, after: u64) -> bool {
    matches!(cfg.opponent, OpponentSpec::SelfPlay { every } if checkpoint_due(before, after, every))
}

fn train_ppo(
    cfg: &TrainConfig,
    out: &Path,
    progress: &mut dyn FnMut(&Progress<'_>),
) -> Result<TrainSummary, LearnError> {
    let mut env = make_env(cfg)?;
    let mut run = RunDir::create(out, cfg)?;
    let mut ppo = Ppo::new(cfg.ppo.clone())?;
    let mut rng = ChaCha8Rng::seed_from_u64(cfg.seed);
    let rows = env.rows();
    let robots = cfg.learners.len();
    let mut tally = Tally::new(robots);
    let mut ro = Rollout::default();
    let (mut actions, mut logp, mut values, mut last_values) = (
        vec![0usize; rows],
        vec![0.0f32; rows],
        vec![0.0f32; rows],
        vec![0.0f32; rows],
    );
    let mut transitions = 0u64;
    let mut update = 0u64;
    let mut out_rows = Vec::new();
    while transitions < cfg.steps {
        ro.clear();
        for _ in 0..cfg.ppo.rollout {
            ro.obs.extend_from_slice(env.observations());
            ppo.act(
                env.observations(),
                &mut rng,
                &mut actions,
                &mut logp,
                &mut values,
            );
            let finished = env.step(&actions)?;
            ro.actions.extend(actions.iter().map(|&a| a as i64));
            ro.logp.extend_from_slice(&logp);
            ro.values.extend_from_slice(&values);
            ro.rewards.extend_from_slice(env.rewards());
            ro.dones
                .extend(env.dones().iter().map(|&d| f32::from(u8::from(d))));
            tally.add_rewards(env.rewards());
            tally.episodes.extend(finished);
        }
        ppo.values(env.observations(), &mut last_values);
        let stats = ppo.update(&ro, rows, &last_values, &mut rng);
        let before = transitions;
        transitions += (cfg.ppo.rollout * rows) as u64;
        update += 1;
        let row = tally.row(
            update,
            env.ticks() / cfg.matches as u64,
            transitions,
            (stats.policy_loss, stats.value_loss, stats.entropy),
        );
        run.write_row(&row)?;
        progress(&Progress {
            row: &row,
            total_steps: cfg.steps,
        });
        out_rows.push(row);
        if checkpoint_due(before, transitions, cfg.checkpoint_every) {
            save_stores(
                &[&ppo.net.vs],
                &out.join(format!("checkpoints/step-{transitions}.safetensors")),
            )?;
        }
        if snapshot_due(cfg, before, transitions) {
            let mut snap = LearnedPolicy::untrained(cfg, "self-play".into());
            snap.copy_from(&[&ppo.net.vs])?;
            env.set_opponent(Opponent::Net(Box::new(snap)));
        }
    }
    let final_weights = out.join("final.safetensors");
    save_stores(&[&ppo.net.vs], &final_weights)?;
    Ok(TrainSummary {
        rows: out_rows,
        transitions,
        final_weights,
    })
}

fn train_dqn(
    cfg: &TrainConfig,
    out: &Path,
    progress: &mut dyn FnMut(&Progress<'_>),
) -> Result<TrainSummary, LearnError> {
    let mut env = make_env(cfg)?;
    let mut run = RunDir::create(out, cfg)?;
    let robots = cfg.learners.len();
    let mut dqn = Dqn::new(cfg.dqn.clone(), robots)?;
    let mut rng = ChaCha8Rng::seed_from_u64(cfg.seed);
    let rows = env.rows();
    let mut tally = Tally::new(robots);
    let mut actions = vec![0usize; rows];
    let mut prev = vec![0.0f32; rows * OBS_DIM];
    let mut transitions = 0u64;
    let mut update = 0u64;
    let (mut loss_sum, mut loss_n) = (0.0, 0u32);
    let mut out_rows = Vec::new();
    let mut step = 0usize;
    let mut nstep = NStep::new(cfg.dqn.n_step, rows);
    // A decision holds its action `action_repeat` ticks (1: every tick).
    let mut held = Held::new(rows, cfg.dqn.action_repeat);
    let tick_discount = cfg.dqn.discount(1);
    while transitions < cfg.steps {
        let deciding = held.any_free();
        if deciding {
            prev.copy_from_slice(env.observations());
            let epsilon = cfg.dqn.epsilon_at(transitions);
            dqn.act(&prev, robots, epsilon, &mut rng, &mut actions);
            held.start(&prev, &actions);
        }
        let finished = env.step(held.actions())?;
        let next = env.observations();
        for i in 0..rows {
            let done = env.dones()[i];
            let Some((ret, discount)) = held.tick(i, env.rewards()[i], tick_discount, done) else {
                continue;
            };
            let next_obs = &next[i * OBS_DIM..(i + 1) * OBS_DIM];
            nstep.push(
                i,
                held.obs(i),
                held.actions()[i],
                ret,
                discount,
                done,
                &mut |t| dqn.remember(i % robots, t.obs, t.action, t.ret, next_obs, t.discount),
            );
        }
        tally.add_rewards(env.rewards());
        tally.episodes.extend(finished);
        if deciding {
            if let Some(l) = dqn.learn(&mut rng) {
                loss_sum += l;
                loss_n += 1;
            }
        }
        let before = transitions;
        transitions += rows as u64;
        step += 1;
        if step.is_multiple_of(cfg.log_every.max(1)) || transitions >= cfg.steps {
            update += 1;
            let loss = if loss_n > 0 {
                loss_sum / f64::from(loss_n)
            } else {
                f64::NAN
            };
            let row = tally.row(
                update,
                env.ticks() / cfg.matches as u64,
                transitions,
                (loss, f64::NAN, f64::NAN),
            );
            loss_sum = 0.0;
            loss_n = 0;
            run.write_row(&row)?;
            progress(&Progress {
                row: &row,
                total_steps: cfg.steps,
            });
            out_rows.push(row);
        }
        let stores: Vec<&tch::nn::VarStore> = dqn.nets.iter().map(|n| &n.vs).collect();
        if checkpoint_due(before, transitions, cfg.checkpoint_every) {
            save_stores(
                &stores,
                &out.join(format!("checkpoints/step-{transitions}.safetensors")),
            )?;
        }
        if snapshot_due(cfg, before, transitions) {
            let mut snap = LearnedPolicy::untrained(cfg, "self-play".into());
            snap.copy_from(&stores)?;
            env.set_opponent(Opponent::Net(Box::new(snap)));
        }
    }
    let final_weights = out.join("final.safetensors");
    let stores: Vec<&tch::nn::VarStore> = dqn.nets.iter().map(|n| &n.vs).collect();
    save_stores(&stores, &final_weights)?;
    Ok(TrainSummary {
        rows: out_rows,
        transitions,
        final_weights,
    })
}
