//! A training run's configuration, saved as its `config.json`: the
//! algorithm, the opponent, the networks' and the match's settings, and the
//! observation encoding they imply; PPO's and DQN's hyperparameters and
//! presets among them. The networks-as-players (`policy`), the
//! schedule's runner and the training loops all read it; it reads none of
//! them.

use naosoccer_policy::actions::{action_count, DecisionConfig};
use naosoccer_policy::PolicyKind;
use naosoccer_referee::MatchConfig;
use serde::{Deserialize, Serialize};

use crate::env::{Drill, ScenarioDrills};
use crate::obs::{ObsScale, OBS_VERSION};
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
    /// Scenarios mixed into the matches (see `env::ScenarioDrills`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub scenarios: Option<ScenarioDrills>,
    /// The pass drills of runs made before they became scenarios: kept so
    /// that such a run's `config.json` still loads (a trained team plays
    /// with it), and refused when such a run is resumed.
    #[serde(default, skip_serializing)]
    pub pass_drills: Option<serde_json::Value>,
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
            scenarios: None,
            pass_drills: None,
            init_from: None,
            init_pass_from: None,
            init_support_bias: None,
        }
    }
}

impl TrainConfig {
    /// The decision-level MDP of the run's algorithm (`None`: every robot
    /// decides every tick).
    pub fn decision(&self) -> Option<DecisionConfig> {
        match self.algo {
            Algo::Ppo => self.ppo.decision,
            Algo::Dqn => self.dqn.decision,
        }
    }
}

/// The observation encoding of a run: its scale under its layout version.
pub fn run_scale(cfg: &TrainConfig) -> ObsScale {
    let mut s = cfg.obs_scale;
    s.version = cfg.obs_version;
    s
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum Preset {
    #[default]
    Paper,
    Cleanrl,
    Team,
}

impl std::str::FromStr for Preset {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "paper" => Ok(Preset::Paper),
            "cleanrl" => Ok(Preset::Cleanrl),
            "team" => Ok(Preset::Team),
            o => Err(format!(
                "unknown PPO preset {o:?} (expected paper, cleanrl or team)"
            )),
        }
    }
}

/// PPO's hyperparameters. `PpoConfig::paper()` and `PpoConfig::cleanrl()`
/// give the presets; docs/LEARNING.md says where each value comes from.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PpoConfig {
    pub preset: Preset,
    pub gamma: f64,
    /// GAE's lambda (cleanrl preset only).
    pub gae_lambda: f64,
    pub clip: f64,
    /// Value-loss weight `c1`.
    pub value_coef: f64,
    /// Entropy-bonus weight `c2`.
    pub entropy_coef: f64,
    pub lr_actor: f64,
    pub lr_critic: f64,
    /// Passes over each rollout.
    pub epochs: usize,
    /// Minibatches a pass is split into (1 = the full batch).
    pub minibatches: usize,
    /// Control ticks each match plays between updates.
    pub rollout: usize,
    /// Gradient-norm clip (cleanrl preset), none when `None`.
    pub max_grad_norm: Option<f64>,
    pub hidden: Vec<usize>,
    /// Stop an update's passes once the approximate KL divergence from the
    /// rollout's policy exceeds 1.5 times this (team preset).
    #[serde(default)]
    pub target_kl: Option<f64>,
    /// The critic predicts returns normalised by their running mean and
    /// standard deviation (team preset).
    #[serde(default)]
    pub value_norm: bool,
    /// Learning rates fall linearly to `lr_end_fraction` of their start
    /// over the run (team preset); constant when `None`.
    #[serde(default)]
    pub lr_end_fraction: Option<f64>,
    /// The entropy weight moves linearly from `entropy_coef` to this over the
    /// run; constant when `None`.
    #[serde(default)]
    pub entropy_coef_end: Option<f64>,
    /// MAPPO: the critic reads the observation vectors of all the team's
    /// learning robots (the acting robot's first), not only the acting one's.
    #[serde(default)]
    pub central_critic: bool,
    /// The decision-level MDP; `None`: every robot decides every tick.
    #[serde(default)]
    pub decision: Option<DecisionConfig>,
}

impl PpoConfig {
    pub fn paper() -> PpoConfig {
        PpoConfig {
            preset: Preset::Paper,
            gamma: 0.99,
            gae_lambda: 1.0,
            clip: 0.2,
            value_coef: 0.5,
            entropy_coef: 0.01,
            lr_actor: 3e-4,
            lr_critic: 1e-3,
            epochs: 80,
            minibatches: 1,
            rollout: 128,
            max_grad_norm: None,
            hidden: vec![64, 64],
            target_kl: None,
            value_norm: false,
            lr_end_fraction: None,
            entropy_coef_end: None,
            central_critic: false,
            decision: None,
        }
    }

    pub fn cleanrl() -> PpoConfig {
        PpoConfig {
            preset: Preset::Cleanrl,
            gamma: 0.99,
            gae_lambda: 0.95,
            clip: 0.2,
            value_coef: 0.5,
            entropy_coef: 0.01,
            lr_actor: 2.5e-4,
            lr_critic: 2.5e-4,
            epochs: 4,
            minibatches: 4,
            rollout: 128,
            max_grad_norm: Some(0.5),
            hidden: vec![64, 64],
            target_kl: None,
            value_norm: false,
            lr_end_fraction: None,
            entropy_coef_end: None,
            central_critic: false,
            decision: None,
        }
    }

    /// The decision-level MDP with the fixes: per-tick gamma 0.995 (a
    /// 200-tick, 20-second horizon), GAE lambda 0.95 per tick, 4 x 4
    /// minibatch passes with a KL stop, value normalisation, annealed
    /// learning rate and entropy, larger networks.
    pub fn team() -> PpoConfig {
        PpoConfig {
            preset: Preset::Team,
            gamma: 0.995,
            gae_lambda: 0.95,
            clip: 0.2,
            value_coef: 0.5,
            entropy_coef: 0.01,
            lr_actor: 3e-4,
            lr_critic: 3e-4,
            epochs: 4,
            minibatches: 4,
            rollout: 256,
            max_grad_norm: Some(0.5),
            hidden: vec![128, 128],
            target_kl: Some(0.02),
            value_norm: true,
            lr_end_fraction: Some(0.1),
            entropy_coef_end: Some(0.002),
            central_critic: false,
            decision: Some(DecisionConfig::team()),
        }
    }

    pub fn preset(p: Preset) -> PpoConfig {
        match p {
            Preset::Paper => PpoConfig::paper(),
            Preset::Cleanrl => PpoConfig::cleanrl(),
            Preset::Team => PpoConfig::team(),
        }
    }

    /// Whether `shoot` is masked out of reach.
    pub fn masks_shoot(&self) -> bool {
        self.decision.is_some_and(|d| d.mask_shoot)
    }

    /// How many actions the actor chooses among: 5, 6 with `pass`, 7 with
    /// `support` too ([`DecisionConfig::actions`]).
    pub fn actions(&self) -> usize {
        action_count(self.decision)
    }
}

/// The DQN hyperparameter sets.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum DqnPreset {
    /// The paper's Algorithm 1 (the default; the shipped `dqn-seed*` teams).
    #[default]
    Paper,
    /// Double DQN, n-step returns, an epsilon schedule, one shared network.
    Team,
}

impl std::str::FromStr for DqnPreset {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "paper" => Ok(DqnPreset::Paper),
            "team" | "dqn-team" => Ok(DqnPreset::Team),
            o => Err(format!("unknown DQN preset {o:?} (expected paper or team)")),
        }
    }
}

/// Missing fields take the `paper` values, so configurations written before
/// a field existed load as the runs that wrote them were trained.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct DqnConfig {
    pub preset: DqnPreset,
    /// Discount per control tick; a transition that lasted `dt` ticks is
    /// discounted by `gamma^dt`.
    pub gamma: f64,
    pub lr: f64,
    /// Probability of a uniformly random action once the schedule has run
    /// out (the paper keeps it fixed); `dqn-epsilon:DIR` plays with it.
    pub epsilon: f64,
    /// The probability at the first transition; it falls linearly to
    /// `epsilon` over `epsilon_decay` transitions (0: fixed at `epsilon`).
    pub epsilon_start: f64,
    pub epsilon_decay: u64,
    /// Hidden widths: four hidden layers make the paper's five linear layers.
    pub hidden: Vec<usize>,
    /// Transitions each replay buffer keeps.
    pub replay: usize,
    pub batch: usize,
    /// Transitions in a buffer before learning starts.
    pub warmup: usize,
    /// Gradient steps between copies to the target network.
    pub target_every: usize,
    /// Gradient steps per network for every vectorised environment step.
    pub updates_per_step: usize,
    /// One network for the team instead of one per robot.
    pub shared: bool,
    /// Double DQN: the online network chooses the next action, the target
    /// network values it (van Hasselt et al. 2016).
    pub double: bool,
    /// Transitions summed into one return before bootstrapping (1: the paper).
    pub n_step: usize,
    /// Huber (smooth L1) loss instead of the paper's MSE.
    pub huber: bool,
    /// Gradient-norm clip (0: none, the paper).
    pub max_grad_norm: f64,
    /// Polyak averaging of the weights: beside each learning network an
    /// average `avg <- average * avg + (1 - average) * net` after every
    /// gradient step, which is the team the run saves (checkpoints,
    /// `final.safetensors`; the learning network's last weights go to
    /// `final-online.safetensors`). 0 (both presets): none, the learning
    /// network is saved. The average never feeds back into learning, so a
    /// run learns the same with it as without.
    pub average: f64,
    /// The decision-level MDP (`None`: every robot decides every tick, the
    /// paper): a robot decides only when free, a movement holds `persist`
    /// ticks, `shoot` may be masked out of reach. A decision is one
    /// transition, its reward the discounted sum over the ticks it lasted
    /// and its discount `gamma^ticks`; learning steps come once per tick in
    /// which some robot decided.
    pub decision: Option<DecisionConfig>,
}

impl Default for DqnConfig {
    fn default() -> Self {
        DqnConfig::paper()
    }
}

impl DqnConfig {
    pub fn preset(p: DqnPreset) -> DqnConfig {
        match p {
            DqnPreset::Paper => DqnConfig::paper(),
            DqnPreset::Team => DqnConfig::team(),
        }
    }

    /// The paper's Algorithm 1, with our choices where it names none
    /// (docs/LEARNING.md).
    pub fn paper() -> DqnConfig {
        DqnConfig {
            preset: DqnPreset::Paper,
            gamma: 0.99,
            lr: 1e-3,
            epsilon: 0.3,
            epsilon_start: 0.3,
            epsilon_decay: 0,
            hidden: vec![128, 128, 128, 128],
            replay: 100_000,
            batch: 128,
            warmup: 1_000,
            target_every: 1_000,
            updates_per_step: 1,
            shared: false,
            double: false,
            n_step: 1,
            huber: false,
            max_grad_norm: 0.0,
            average: 0.0,
            decision: None,
        }
    }

    /// Double DQN with 3-step returns, Huber loss, clipped gradients, epsilon
    /// falling from 1 to 0.05 over the first million transitions, one
    /// network for the team fed by all four robots, on the decision-level
    /// MDP of PPO's `team` preset (movements hold 3 ticks, `shoot` masked
    /// out of reach, gamma 0.995 per tick).
    pub fn team() -> DqnConfig {
        DqnConfig {
            preset: DqnPreset::Team,
            gamma: 0.995,
            lr: 2.5e-4,
            epsilon: 0.05,
            epsilon_start: 1.0,
            epsilon_decay: 1_000_000,
            hidden: vec![256, 256],
            replay: 300_000,
            batch: 256,
            warmup: 20_000,
            target_every: 2_000,
            updates_per_step: 1,
            shared: true,
            double: true,
            n_step: 3,
            huber: true,
            max_grad_norm: 10.0,
            average: 0.0,
            decision: Some(DecisionConfig::team()),
        }
    }

    /// How many actions the Q-network values: 5 (the paper's, and the
    /// `team` preset's by default), up to 10 with the decision settings'
    /// extra actions ([`DecisionConfig::actions`]).
    pub fn actions(&self) -> usize {
        action_count(self.decision)
    }

    /// The exploration rate after `transitions` robot transitions.
    pub fn epsilon_at(&self, transitions: u64) -> f64 {
        if self.epsilon_decay == 0 || transitions >= self.epsilon_decay {
            return self.epsilon;
        }
        let left = 1.0 - transitions as f64 / self.epsilon_decay as f64;
        self.epsilon + (self.epsilon_start - self.epsilon) * left
    }

    /// The discount of a transition that lasted `dt` control ticks.
    pub fn discount(&self, dt: u32) -> f32 {
        self.gamma.powi(dt as i32) as f32
    }
}
