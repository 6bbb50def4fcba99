//! Loading a trained team: what playing reads of a run's `config.json`,
//! where a run directory keeps its weights, and the specs (`ppo:DIR`,
//! `dqn:DIR`, ...) that name a team.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use super::{ActMode, LearnedPolicy};
use crate::actions::DecisionConfig;
use crate::mlp::Weights;
use crate::obs::{layout_dim, ObsScale, OBS_VERSION_LATEST};
use crate::{Policy, PolicyError};

/// The learning algorithm a run used.
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

/// What playing needs of a run's `config.json` (the trainer's
/// `TrainConfig`; its other fields are ignored here).
#[derive(Debug, Clone, PartialEq, Deserialize)]
pub struct PlayConfig {
    pub algo: Algo,
    /// Players the networks were trained on, in the order of the per-robot
    /// DQN networks.
    pub learners: Vec<usize>,
    pub obs_version: u32,
    pub obs_scale: ObsScale,
    #[serde(default)]
    pub ppo: PpoPlay,
    #[serde(default)]
    pub dqn: DqnPlay,
}

/// The PPO fields playing reads.
#[derive(Debug, Clone, Default, PartialEq, Deserialize)]
pub struct PpoPlay {
    #[serde(default)]
    pub decision: Option<DecisionConfig>,
}

/// The DQN fields playing reads; missing ones take the `paper` preset's
/// values, as the trainer's configuration does.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(default)]
pub struct DqnPlay {
    pub shared: bool,
    pub epsilon: f64,
    pub decision: Option<DecisionConfig>,
}

impl Default for DqnPlay {
    fn default() -> Self {
        DqnPlay {
            shared: false,
            epsilon: 0.3,
            decision: None,
        }
    }
}

impl PlayConfig {
    /// Reads a run's `config.json`.
    pub fn read(path: &Path) -> Result<PlayConfig, PolicyError> {
        let text = std::fs::read_to_string(path).map_err(|e| PolicyError::io(path, e))?;
        serde_json::from_str(&text).map_err(|e| PolicyError::Json {
            path: path.to_path_buf(),
            error: e,
        })
    }

    /// The observation encoding: the scale under the run's layout version.
    pub fn scale(&self) -> ObsScale {
        let mut s = self.obs_scale;
        s.version = self.obs_version;
        s
    }

    /// The decision-level MDP the run trained in, if any.
    pub fn decision(&self) -> Option<DecisionConfig> {
        match self.algo {
            Algo::Ppo => self.ppo.decision,
            Algo::Dqn => self.dqn.decision,
        }
    }

    /// How many DQN networks the run has (one per learner unless shared).
    pub fn dqn_nets(&self) -> usize {
        if self.dqn.shared {
            1
        } else {
            self.learners.len()
        }
    }
}

/// Loads `ppo:DIR`, `ppo-greedy:DIR`, `dqn:DIR` (a run directory) or
/// `ppo:FILE.safetensors` (a checkpoint inside a run directory) as a boxed
/// `Policy`, sampling (if it samples) as in a match of seed 0.
pub fn load_policy(spec: &str) -> Result<Box<dyn Policy>, PolicyError> {
    load_policy_for_match(spec, 0)
}

/// As [`load_policy`], for a match of seed `match_seed`: the policy the
/// server's fill and `naosoccer client` build for each match (in process,
/// one `LearnedPolicy` plays a whole side of many matches, keyed by their
/// seeds: the same actions).
pub fn load_policy_for_match(spec: &str, match_seed: u64) -> Result<Box<dyn Policy>, PolicyError> {
    let mut p = LearnedPolicy::load(spec)?;
    p.set_match_seed(match_seed);
    Ok(Box::new(p))
}

/// Where a run directory keeps its configuration and weights.
pub fn resolve_run(path: &Path) -> Result<(PathBuf, PathBuf), PolicyError> {
    if path.extension().is_some_and(|e| e == "safetensors") {
        if !path.is_file() {
            return Err(PolicyError::io(
                path,
                std::io::Error::new(std::io::ErrorKind::NotFound, "no such weights file"),
            ));
        }
        // checkpoints/step-N.safetensors -> the run directory two levels up.
        let mut dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
        if !dir.join("config.json").exists() {
            dir = dir.parent().map(Path::to_path_buf).unwrap_or_default();
        }
        return Ok((dir.join("config.json"), path.to_path_buf()));
    }
    if !path.exists() {
        return Err(PolicyError::Spec {
            spec: path.display().to_string(),
            reason: "no such directory (a team directory holds config.json and \
                     final.safetensors, or a run's checkpoints/)"
                .into(),
        });
    }
    if !path.is_dir() {
        return Err(PolicyError::Spec {
            spec: path.display().to_string(),
            reason: "not a directory or a .safetensors file".into(),
        });
    }
    let cfg = path.join("config.json");
    let fin = path.join("final.safetensors");
    if fin.exists() {
        return Ok((cfg, fin));
    }
    latest_checkpoint(path)
        .map(|c| (cfg, c))
        .ok_or_else(|| PolicyError::Spec {
            spec: path.display().to_string(),
            reason: "no final.safetensors and no checkpoints/step-*.safetensors in it".into(),
        })
}

fn latest_checkpoint(dir: &Path) -> Option<PathBuf> {
    let rd = std::fs::read_dir(dir.join("checkpoints")).ok()?;
    let mut best: Option<(u64, PathBuf)> = None;
    for e in rd.flatten() {
        let p = e.path();
        let Some(n) = p
            .file_name()
            .and_then(|n| n.to_str())
            .and_then(|n| n.strip_prefix("step-"))
            .and_then(|n| n.strip_suffix(".safetensors"))
            .and_then(|n| n.parse::<u64>().ok())
        else {
            continue;
        };
        if best.as_ref().is_none_or(|(b, _)| n > *b) {
            best = Some((n, p));
        }
    }
    best.map(|(_, p)| p)
}

/// Whether `spec` names a trained team (`ppo:`, `ppo-greedy:`, `dqn:`,
/// `dqn-epsilon:`), as opposed to a built-in one.
pub fn is_learned_spec(spec: &str) -> bool {
    spec.split_once(':')
        .is_some_and(|(k, _)| matches!(k, "ppo" | "ppo-greedy" | "dqn" | "dqn-epsilon"))
}

impl LearnedPolicy {
    /// Parses `algo:PATH` and loads it; the algorithm must match the run's.
    pub fn load(spec: &str) -> Result<LearnedPolicy, PolicyError> {
        let bad = |reason: &str| PolicyError::Spec {
            spec: spec.to_string(),
            reason: reason.to_string(),
        };
        let (kind, path) = spec
            .split_once(':')
            .ok_or_else(|| bad("expected ppo:DIR, ppo-greedy:DIR, dqn:DIR or dqn-epsilon:DIR"))?;
        let algo = match kind {
            "ppo" | "ppo-greedy" => Algo::Ppo,
            "dqn" | "dqn-epsilon" => Algo::Dqn,
            other => {
                return Err(bad(&format!(
                    "unknown kind {other:?} (expected ppo, ppo-greedy, dqn or dqn-epsilon)"
                )))
            }
        };
        let (cfg_path, weights) = resolve_run(Path::new(path))?;
        let cfg = PlayConfig::read(&cfg_path)?;
        if cfg.algo != algo {
            return Err(bad(&format!("{} was trained with {}", path, cfg.algo)));
        }
        if layout_dim(cfg.obs_version).is_none() {
            return Err(PolicyError::ObsVersion {
                path: cfg_path,
                found: cfg.obs_version,
                expected: OBS_VERSION_LATEST,
            });
        }
        let mut p =
            LearnedPolicy::from_weights(&cfg, &Weights::read(&weights)?, format!("{kind}:{path}"))?;
        p.mode = match kind {
            "ppo" => ActMode::Sample,
            "dqn-epsilon" => ActMode::EpsilonGreedy {
                epsilon: cfg.dqn.epsilon as f32,
            },
            _ => ActMode::Greedy,
        };
        Ok(p)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A missing weights file or run is named once, in words a user can act
    /// on (the io error's text used to appear twice in the CLI's report).
    #[test]
    fn missing_runs_are_named_once() {
        let dir = std::env::temp_dir().join("naosoccer-policy-missing-run");
        let file = dir.join("MISSING.safetensors");
        let err = LearnedPolicy::load(&format!("ppo:{}", file.display())).unwrap_err();
        assert!(std::error::Error::source(&err).is_none());
        let msg = err.to_string();
        assert_eq!(msg, format!("{}: no such weights file", file.display()));
        // A directory that does not exist is said to be missing...
        let err = LearnedPolicy::load(&format!("ppo:{}", dir.display())).unwrap_err();
        assert!(err.to_string().contains("no such directory"), "{err}");
        // ...and one that exists but holds no weights says what is missing.
        let empty =
            std::env::temp_dir().join(format!("naosoccer-policy-empty-run-{}", std::process::id()));
        std::fs::create_dir_all(&empty).unwrap();
        let err = LearnedPolicy::load(&format!("ppo:{}", empty.display())).unwrap_err();
        std::fs::remove_dir_all(&empty).ok();
        assert!(err.to_string().contains("no final.safetensors"), "{err}");
    }

    /// A team whose decision section has a setting this build does not know
    /// (a run from a newer build) is refused, naming the setting, instead
    /// of playing without it.
    #[test]
    fn unknown_decision_settings_are_refused() {
        let shipped =
            Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/policies/ppo-team-seed1");
        let dir = std::env::temp_dir().join("naosoccer-policy-unknown-decision");
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::copy(
            shipped.join("final.safetensors"),
            dir.join("final.safetensors"),
        )
        .unwrap();
        let mut cfg: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(shipped.join("config.json")).unwrap())
                .unwrap();
        std::fs::write(dir.join("config.json"), cfg.to_string()).unwrap();
        let spec = format!("ppo:{}", dir.display());
        assert!(
            LearnedPolicy::load(&spec).is_ok(),
            "the copy loads as it is"
        );
        cfg["ppo"]["decision"]["sidekicks"] = serde_json::json!(2);
        std::fs::write(dir.join("config.json"), cfg.to_string()).unwrap();
        let err = LearnedPolicy::load(&spec).unwrap_err().to_string();
        assert!(err.contains("unknown field `sidekicks`"), "{err}");
        assert!(err.contains("config.json"), "{err}");
    }
}
