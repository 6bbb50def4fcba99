//! A training run's configuration, saved as its `config.json`: the
//! algorithm, the opponent, the networks' and the match's settings, and the
//! observation encoding they imply. The networks-as-players (`policy`), the
//! schedule's runner and the training loops all read it; it reads none of
//! them.

use naosoccer_client::PolicyKind;
use naosoccer_referee::MatchConfig;
use serde::{Deserialize, Serialize};

use crate::dqn::DqnConfig;
use crate::env::{Drill, PassDrills};
use crate::obs::{ObsScale, OBS_VERSION};
use crate::ppo::PpoConfig;
use crate::schedule::Schedule;

pub use naosoccer_policy::Algo;

/// Who the learner plays against during training.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum OpponentSpec {
    /// A built-in policy by spec: `scripted`, `scripted:KEY=VAL,...`,
    /// `random`, `idle`.
    Builtin(String),
    /// A frozen trained team, `ppo:DIR` or `dqn:DIR`.
    Frozen(String),
    /// The learner's own snapshot, refreshed every `every` transitions.
    SelfPlay { every: u64 },
    /// A curriculum of opponent mixes with a pool of past snapshots (PPO).
    Schedule(Schedule),
}

impl std::str::FromStr for OpponentSpec {
    type Err = String;
    /// `scripted` | `random` | `idle` | `ppo:DIR` | `dqn:DIR` | `self-play[:N]`
    /// | `curriculum` | `schedule:STAGES` (see [`crate::schedule`]).
    fn from_str(s: &str) -> Result<Self, String> {
        if s == "curriculum" {
            return Ok(OpponentSpec::Schedule(Schedule::curriculum()));
        }
        if let Some(rest) = s.strip_prefix("schedule:") {
            return Schedule::parse(rest).map(OpponentSpec::Schedule);
        }
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
        let kind = s.parse::<PolicyKind>().map_err(|e| {
            format!("{e}; or ppo:DIR, dqn:DIR, self-play[:N], curriculum, schedule:...")
        })?;
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
    /// Drill episodes instead of matches (see `env::Drill`).
    #[serde(default)]
    pub drill: Option<Drill>,
    /// Pass drills mixed into the matches (see `env::PassDrills`).
    #[serde(default)]
    pub pass_drills: Option<PassDrills>,
    /// PPO team preset: the run starts from these weights (a finished run's
    /// `final.safetensors`, or a checkpoint) instead of fresh ones, with a
    /// fresh optimiser. An actor trained without `pass` gains it, its
    /// logit starting as a copy of `shoot`'s (or `init_pass_from`'s).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub init_from: Option<std::path::PathBuf>,
    /// With `init_from`: whose output row a gained `pass` row copies
    /// (`shoot` when unset). `turn_left` starts a kicker that tries `pass`
    /// where it used to turn with the ball (docs/LEARNING.md).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub init_pass_from: Option<naosoccer_proto::Action>,
    /// With `init_from`: how much lower (in logits) a gained `support`
    /// row's bias starts than `forward`'s ([`crate::warm_start::SUPPORT_INIT_BIAS`]
    /// when unset; 0 starts `support` as likely as `forward`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub init_support_bias: Option<f32>,
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
            drill: None,
            pass_drills: None,
            init_from: None,
            init_pass_from: None,
            init_support_bias: None,
        }
    }
}

/// The observation encoding of a run: its scale under its layout version.
pub fn run_scale(cfg: &TrainConfig) -> ObsScale {
    let mut s = cfg.obs_scale;
    s.version = cfg.obs_version;
    s
}
