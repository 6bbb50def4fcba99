//! Resumable checkpoints (team-preset PPO runs): what one holds, writing
//! and reading it, and finding where a stopped run goes on.

use std::path::Path;

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};
use tch::nn::VarStore;

use crate::adam::Adam;
use crate::config::{Algo, TrainConfig};
use crate::policy::save_stores;
use crate::LearnError;

/// Where a decision-level run stands at a checkpoint (an episode boundary):
/// with the weights (`step-N.safetensors`) and the optimiser's moments
/// (`step-N.adam.safetensors`), everything `train --resume` needs to go on
/// as if the run had not stopped. Saved as `checkpoints/step-N.resume.json`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ResumeState {
    pub transitions: u64,
    pub update: u64,
    pub env_ticks: u64,
    /// Each match's next episode number.
    pub episodes: Vec<u64>,
    pub total_episodes: u64,
    /// The ChaCha8 stream (sampling, minibatch order): seed, stream and
    /// word position (a decimal string: it is a u128).
    pub rng_seed: [u8; 32],
    pub rng_stream: u64,
    pub rng_word_pos: String,
    pub value_norm: crate::nets::RunningNorm,
    /// The opponent schedule's stage and snapshot pool.
    pub schedule: Option<(usize, Vec<(u64, String)>)>,
    /// The self-play snapshot in play (a file in `pool/`).
    pub self_play: Option<String>,
}

impl ResumeState {
    pub(crate) fn rng(&self) -> Result<ChaCha8Rng, LearnError> {
        let mut r = ChaCha8Rng::from_seed(self.rng_seed);
        r.set_stream(self.rng_stream);
        r.set_word_pos(self.rng_word_pos.parse::<u128>().map_err(|_| {
            LearnError::Config(format!("bad RNG position {:?}", self.rng_word_pos))
        })?);
        Ok(r)
    }
}

/// Writes a resumable checkpoint: the weights of `live`, the optimiser's
/// moments and `state`.
pub(crate) fn write_checkpoint(
    out: &Path,
    live: &VarStore,
    adam: Option<&Adam>,
    state: &ResumeState,
) -> Result<(), LearnError> {
    let ck = out.join("checkpoints");
    let n = state.transitions;
    save_stores(&[live], &ck.join(format!("step-{n}.safetensors")))?;
    if let Some(a) = adam {
        tch::Tensor::write_safetensors(&a.state(), ck.join(format!("step-{n}.adam.safetensors")))?;
    }
    let path = ck.join(format!("step-{n}.resume.json"));
    let json = serde_json::to_string_pretty(state).map_err(|e| LearnError::json(&path, e))?;
    // Written last, and whole or not at all (a temporary file renamed): a
    // checkpoint counts once its resume state exists, so a run killed at
    // any moment (Ctrl-C) resumes from its last complete checkpoint.
    let tmp = path.with_extension("json.tmp");
    std::fs::write(&tmp, json).map_err(|e| LearnError::io(&tmp, e))?;
    std::fs::rename(&tmp, &path).map_err(|e| LearnError::io(&path, e))
}

/// Loads a resumable checkpoint's weights into `live` and its
/// optimiser's moments into `adam`.
pub(crate) fn read_checkpoint(
    out: &Path,
    st: &ResumeState,
    live: &mut VarStore,
    adam: Option<&mut Adam>,
) -> Result<(), LearnError> {
    let ck = out.join("checkpoints");
    live.load(ck.join(format!("step-{}.safetensors", st.transitions)))?;
    let named = tch::Tensor::read_safetensors(
        ck.join(format!("step-{}.adam.safetensors", st.transitions)),
    )?;
    if let Some(a) = adam {
        a.load_state(&named)?;
    }
    Ok(())
}

/// The configuration of the run in `dir` (its length replaced by `steps`
/// and its thread count by `threads`, if given, and saved so) and the
/// state of its latest resumable checkpoint (decision-level PPO runs).
pub(crate) fn resume_point(
    dir: &Path,
    steps: Option<u64>,
    threads: Option<usize>,
) -> Result<(TrainConfig, ResumeState), LearnError> {
    let cfg_path = dir.join("config.json");
    let text = std::fs::read_to_string(&cfg_path).map_err(|e| LearnError::io(&cfg_path, e))?;
    let mut cfg: TrainConfig =
        serde_json::from_str(&text).map_err(|e| LearnError::json(&cfg_path, e))?;
    if cfg.algo != Algo::Ppo || cfg.ppo.decision.is_none() {
        return Err(LearnError::Config(
            "--resume continues decision-level PPO runs (--preset team) only".into(),
        ));
    }
    if steps.is_some() || threads.is_some() {
        cfg.steps = steps.unwrap_or(cfg.steps);
        cfg.threads = threads.unwrap_or(cfg.threads);
        let json =
            serde_json::to_string_pretty(&cfg).map_err(|e| LearnError::json(&cfg_path, e))?;
        std::fs::write(&cfg_path, json).map_err(|e| LearnError::io(&cfg_path, e))?;
    }
    let ck = dir.join("checkpoints");
    let mut best: Option<u64> = None;
    if let Ok(rd) = std::fs::read_dir(&ck) {
        for e in rd.flatten() {
            let name = e.file_name().to_string_lossy().into_owned();
            if let Some(n) = name
                .strip_prefix("step-")
                .and_then(|n| n.strip_suffix(".resume.json"))
                .and_then(|n| n.parse::<u64>().ok())
            {
                best = best.max(Some(n));
            }
        }
    }
    let n = best.ok_or_else(|| naosoccer_policy::PolicyError::Spec {
        spec: dir.display().to_string(),
        reason: "no checkpoints/step-N.resume.json to resume from".into(),
    })?;
    let path = ck.join(format!("step-{n}.resume.json"));
    let text = std::fs::read_to_string(&path).map_err(|e| LearnError::io(&path, e))?;
    let state: ResumeState = serde_json::from_str(&text).map_err(|e| LearnError::json(&path, e))?;
    Ok((cfg, state))
}
