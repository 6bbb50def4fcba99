//! The policy crate's errors.

use std::path::PathBuf;

/// Why loading or playing a trained team failed.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum PolicyError {
    #[error("match: {0}")]
    Match(#[from] naosoccer_referee::MatchError),
    // The cause is part of the message and deliberately not a `source`:
    // error reporters that print the chain (anyhow's) would say it twice.
    #[error("{path}: {error}")]
    Io {
        path: PathBuf,
        error: std::io::Error,
    },
    #[error("{path}: invalid JSON: {error}")]
    Json {
        path: PathBuf,
        error: serde_json::Error,
    },
    #[error("invalid policy spec {spec:?}: {reason}")]
    Spec { spec: String, reason: String },
    #[error("{path}: trained on observation layout v{found}, this build reads v1 to v{expected}")]
    ObsVersion {
        path: PathBuf,
        found: u32,
        expected: u32,
    },
    /// A checkpoint lacks a tensor the network needs, or holds one of the
    /// wrong shape or type.
    #[error("weights {name}: {reason}")]
    Weights { name: String, reason: String },
}

impl PolicyError {
    pub(crate) fn io(path: impl Into<PathBuf>, source: std::io::Error) -> PolicyError {
        PolicyError::Io {
            path: path.into(),
            error: source,
        }
    }
}
