//! Who plays against the learner, and how each episode draws its opponent
//! from a weighted mix.

use naosoccer_policy::PolicyKind;

use super::episode_seed;
use crate::LearnError;
use naosoccer_policy::BatchActor;

/// Who plays against the learner.
pub enum Opponent {
    /// A built-in policy, one instance per robot.
    Builtin(PolicyKind),
    /// A network (frozen checkpoint or self-play snapshot), batched over all
    /// matches.
    Net(Box<dyn BatchActor>),
}

impl Opponent {
    fn builtin_kind(&self) -> Option<PolicyKind> {
        match self {
            Opponent::Builtin(k) => Some(*k),
            Opponent::Net(_) => None,
        }
    }
}

/// How each episode picks its opponent: by weight, from a hash of the run's
/// seed, the match index and the episode (so the choice does not depend on
/// threads or on when it is asked).
#[derive(Debug, Clone)]
pub(super) struct Mix {
    pub(super) kinds: Vec<Option<PolicyKind>>,
    /// Cumulative weights, normalised to end at 1.
    cumulative: Vec<f64>,
}

impl Mix {
    pub(super) fn new(opponents: &[Opponent], weights: &[f64]) -> Result<Mix, LearnError> {
        let total: f64 = weights.iter().sum();
        if opponents.is_empty()
            || opponents.len() != weights.len()
            || weights.iter().any(|w| !w.is_finite() || *w < 0.0)
            || !total.is_finite()
            || total <= 0.0
        {
            return Err(LearnError::Config(format!(
                "opponent weights {weights:?} for {} opponents",
                opponents.len()
            )));
        }
        let mut acc = 0.0;
        Ok(Mix {
            kinds: opponents.iter().map(Opponent::builtin_kind).collect(),
            cumulative: weights
                .iter()
                .map(|w| {
                    acc += w / total;
                    acc
                })
                .collect(),
        })
    }

    pub(super) fn pick(&self, seed: u64, index: usize, episode: u64) -> usize {
        let u = (episode_seed(seed ^ 0x5EED_0FF0_0000_0001, index, episode) >> 11) as f64
            / (1u64 << 53) as f64;
        self.cumulative
            .iter()
            .position(|&c| u < c)
            .unwrap_or(self.cumulative.len() - 1)
    }
}
