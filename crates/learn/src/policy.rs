//! The trainer's networks as players. Every trained team plays through
//! `naosoccer-policy`'s forward pass (plain Rust, no libtorch): a frozen
//! opponent loaded from a run directory, and a self-play or pool snapshot of
//! the live networks, whose variables are copied out of their `VarStore`s.
//! This module only converts and sets how a snapshot plays; how a team acts
//! is `naosoccer_policy::learned`.

use std::path::Path;

use tch::nn::VarStore;
use tch::{Kind, Tensor};

pub use naosoccer_policy::actions::{is_free, sample_uniform, Hold};
pub use naosoccer_policy::learned::{resolve_run, ActMode, LearnedPolicy, PlayConfig};
pub use naosoccer_policy::{load_policy, load_policy_for_match, Weights};

use crate::config::{run_scale, Algo, TrainConfig};
use crate::nets::ActorCritic;
use crate::nets::QNet;
use crate::LearnError;

/// What playing reads of a training configuration (the fields of its
/// config.json that `naosoccer-policy` reads).
pub fn play_config(cfg: &TrainConfig) -> Result<PlayConfig, LearnError> {
    let json = serde_json::to_value(cfg).map_err(|e| LearnError::Config(e.to_string()))?;
    serde_json::from_value(json).map_err(|e| LearnError::Config(e.to_string()))
}

/// The variables of `stores` as named f32 tensors (their names are distinct
/// by construction: `actor.*`, `critic.*`, `q0.*`, ...).
pub fn weights_of(stores: &[&VarStore]) -> Weights {
    let mut w = Weights::default();
    for vs in stores {
        for (name, t) in vs.variables() {
            let t = t.detach().to_kind(Kind::Float).contiguous();
            let shape: Vec<usize> = t.size().iter().map(|&d| d as usize).collect();
            let n: usize = shape.iter().product();
            let mut data = vec![0.0f32; n];
            t.copy_data(&mut data, n);
            w.insert(name, shape, data);
        }
    }
    w
}

/// The team of `stores`' networks, configured as `cfg` says, acting greedily
/// until told otherwise.
pub fn from_stores(
    cfg: &TrainConfig,
    stores: &[&VarStore],
    name: String,
) -> Result<LearnedPolicy, LearnError> {
    Ok(LearnedPolicy::from_weights(
        &play_config(cfg)?,
        &weights_of(stores),
        name,
    )?)
}

/// The networks `cfg` describes, freshly initialised by tch (the first
/// self-play snapshot is the untrained learner).
pub fn untrained(cfg: &TrainConfig, name: String) -> Result<LearnedPolicy, LearnError> {
    let scale = run_scale(cfg);
    match cfg.algo {
        Algo::Ppo => {
            let ac = ActorCritic::for_run(&cfg.ppo, &scale, cfg.learners.len());
            from_stores(cfg, &[&ac.vs], name)
        }
        Algo::Dqn => {
            let n = if cfg.dqn.shared {
                1
            } else {
                cfg.learners.len()
            };
            let nets: Vec<QNet> = (0..n)
                .map(|i| {
                    let (hidden, actions) = (&cfg.dqn.hidden, cfg.dqn.actions());
                    QNet::with_input(scale.dim(), hidden, actions, &format!("q{i}"))
                })
                .collect();
            let stores: Vec<&VarStore> = nets.iter().map(|n| &n.vs).collect();
            from_stores(cfg, &stores, name)
        }
    }
}

/// A self-play opponent: the run's networks (fresh when `weights` is `None`,
/// else a copy of the live training networks). It plays as the learner's
/// team would (`ppo:` samples, `dqn:` is greedy), its draws keyed by each
/// match's seed, and under the decision-level MDP it holds its decisions as
/// a loaded team does. Every snapshot, the first and each refresh, is built
/// here (issue 13, cause 1: refreshed snapshots used to play greedily).
pub fn self_play_snapshot(
    cfg: &TrainConfig,
    weights: Option<&[&tch::nn::VarStore]>,
) -> Result<LearnedPolicy, LearnError> {
    let mut p = match weights {
        Some(w) => from_stores(cfg, w, "self-play".into())?,
        None => untrained(cfg, "self-play".into())?,
    };
    p.set_mode(match cfg.algo {
        Algo::Ppo => ActMode::Sample,
        Algo::Dqn => ActMode::Greedy,
    });
    p.set_match_seed(cfg.seed);
    Ok(p)
}

/// Saves several stores into one safetensors file (their variable names are
/// distinct by construction).
pub fn save_stores(stores: &[&VarStore], path: &Path) -> Result<(), LearnError> {
    let mut named: Vec<(String, Tensor)> = Vec::new();
    for vs in stores {
        let mut vars: Vec<(String, Tensor)> = vs.variables().into_iter().collect();
        // Sorted, so the same weights give the same file bytes.
        vars.sort_by(|a, b| a.0.cmp(&b.0));
        named.extend(vars);
    }
    Tensor::write_safetensors(&named, path)?;
    Ok(())
}
