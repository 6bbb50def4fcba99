//! Match recordings: every match to MCAP, and every recording re-simulated
//! bit for bit.
//!
//! - [`Recorder`] writes a match as it is played: metadata (config, seed,
//!   teams, versions), each control tick's applied actions (all that
//!   re-simulation needs), each tick's state with its hash, referee events,
//!   the final statistics, and Foxglove channels (`foxglove.SceneUpdate`,
//!   `foxglove.FrameTransforms`: the Foxglove SDK's types, protobuf) so a
//!   file opens as a 3D scene.
//! - [`Recording::read`] reads one back, also a file cut short by a killed
//!   writer (it keeps every completed chunk and says it was truncated).
//! - [`replay`] re-simulates a recording (the recorded state changes,
//!   `set_state`, re-applied before the tick they preceded) and reports the
//!   first tick whose state differs, or that all are identical.
//!
//! Game time is the only clock in a recording (log time = tick / control
//! rate), and compression runs on the writer's thread, so the same match
//! gives the same bytes.

/// The Foxglove scene: also what `--live` streams.
pub mod foxglove;
mod messages;
mod reader;
mod replay;
mod writer;

pub use messages::{
    BallRecord, FinalRecord, MatchMeta, RobotRecord, ScenarioRecord, ScoreRecord, SetStateRecord,
    StateRecord, TickActions, OLDEST_READABLE_FORMAT, RECORDING_FORMAT,
};
pub use reader::Recording;
pub use replay::{recorded_start, replay, ReplayOutcome};
pub use writer::{Recorder, RecorderOptions, RecordingSummary, Sink};

/// Topics, in the order their channels are created.
pub mod topics {
    pub const META: &str = "/match/meta";
    pub const ACTIONS: &str = "/match/actions";
    pub const STATE: &str = "/match/state";
    pub const EVENTS: &str = "/match/events";
    pub const STATS: &str = "/match/stats";
    pub const SCENE: &str = "/foxglove/scene";
    pub const TF: &str = "/foxglove/tf";
    pub const ALL: [&str; 7] = [META, ACTIONS, STATE, EVENTS, STATS, SCENE, TF];
    /// State changes an admin made (protocol 1.5's `set_state`): created
    /// with the first one, so a recording without any has the seven above.
    pub const SET_STATE: &str = "/match/set_state";
}

/// What can go wrong with a recording.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum RecordError {
    #[error("recording I/O: {0}")]
    Io(#[from] std::io::Error),
    #[error("MCAP: {0}")]
    Mcap(#[from] mcap::McapError),
    #[error("JSON in channel {topic}: {source}")]
    Json {
        topic: String,
        #[source]
        source: serde_json::Error,
    },
    #[error("not a naosoccer recording: {0}")]
    NotARecording(String),
    #[error("recording format {found} is not supported (this build reads {oldest} to {newest})")]
    UnsupportedFormat {
        found: u32,
        oldest: u32,
        newest: u32,
    },
    #[error("cannot re-create the match: {0}")]
    Match(#[from] naosoccer_referee::MatchError),
    #[error("cannot re-create the match's scenario: {0}")]
    Scenario(#[from] naosoccer_referee::ScenarioError),
}
