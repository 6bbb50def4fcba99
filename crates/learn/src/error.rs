//! The learning crate's errors.

use std::path::PathBuf;

/// Why training, loading or evaluating failed.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum LearnError {
    #[error("match: {0}")]
    Match(#[from] naosoccer_referee::MatchError),
    #[error("{0}")]
    Policy(#[from] naosoccer_policy::PolicyError),
    #[error("libtorch: {0}")]
    Torch(#[from] tch::TchError),
    #[error("{path}: {source}")]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("{path}: invalid JSON: {source}")]
    Json {
        path: PathBuf,
        #[source]
        source: serde_json::Error,
    },
    #[error("invalid policy spec {spec:?}: {reason}")]
    Spec { spec: String, reason: String },
    #[error("{path}: trained on observation layout v{found}, this build reads v{expected}")]
    ObsVersion {
        path: PathBuf,
        found: u32,
        expected: u32,
    },
    #[error("invalid configuration: {0}")]
    Config(String),
    #[error("plot: {0}")]
    Plot(String),
}

impl LearnError {
    pub(crate) fn io(path: impl Into<PathBuf>, source: std::io::Error) -> LearnError {
        LearnError::Io {
            path: path.into(),
            source,
        }
    }
}
