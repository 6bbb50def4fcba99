//! The learning crate's errors.

use std::path::PathBuf;

use naosoccer_policy::PolicyError;

/// Why training, loading or evaluating failed.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum LearnError {
    #[error("match: {0}")]
    Match(#[from] naosoccer_referee::MatchError),
    /// Loading or saving files (I/O, JSON, policy specs, observation
    /// layouts, weights): the policy crate's errors, shared rather than
    /// repeated here.
    #[error(transparent)]
    Policy(#[from] PolicyError),
    #[error("libtorch: {0}")]
    Torch(#[from] tch::TchError),
    #[error("invalid configuration: {0}")]
    Config(String),
    #[error("plot: {0}")]
    Plot(String),
}

impl LearnError {
    pub(crate) fn io(path: impl Into<PathBuf>, source: std::io::Error) -> LearnError {
        LearnError::Policy(PolicyError::Io {
            path: path.into(),
            error: source,
        })
    }

    pub(crate) fn json(path: impl Into<PathBuf>, source: serde_json::Error) -> LearnError {
        LearnError::Policy(PolicyError::Json {
            path: path.into(),
            error: source,
        })
    }
}
