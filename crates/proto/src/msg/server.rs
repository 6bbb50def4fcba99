//! Server to client: the replies, and what the server pushes to a joined
//! client (observations, the match's end).

use serde::{Deserialize, Serialize};

use super::{ErrorMsg, Fill, MatchId, Mode, PerTeam, Player, Score, Version};
use crate::types::{Event, MatchStats, Observation, Team, Tick, PLAYERS_PER_TEAM};

/// Everything a server sends.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case")]
pub enum ServerMsg {
    Welcome(Welcome),
    MatchCreated(MatchCreated),
    MatchList(MatchList),
    Joined(Joined),
    Observation(ObservationMsg),
    MatchEnd(MatchEnd),
    Left(Left),
    Pong(Pong),
    MatchEnded(MatchEnded),
    StateSet(StateSet),
    Error(ErrorMsg),
    /// A `type` this build does not know (from a newer minor version); skip it.
    #[serde(other, skip_serializing)]
    Unknown,
}

#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Welcome {
    pub protocol: String,
    pub version: Version,
    /// Server software and version, for logs.
    pub server: String,
    /// The largest frame payload the server accepts, in bytes.
    pub max_frame: u32,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MatchCreated {
    pub info: MatchInfo,
}

/// The reply to `end_match`: the match as it ended (protocol 1.2).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MatchEnded {
    pub info: MatchInfo,
}

/// The reply to `set_state` (protocol 1.5): the state was set before tick
/// `tick` of the match was played.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct StateSet {
    pub match_id: MatchId,
    pub tick: Tick,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MatchList {
    pub matches: Vec<MatchInfo>,
}

/// Where a match is in its life.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum MatchState {
    /// Waiting for `start_players` robots to join.
    Waiting,
    Running,
    Finished,
}

/// A match as `list_matches` and `match_created` describe it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MatchInfo {
    pub match_id: MatchId,
    pub state: MatchState,
    pub mode: Mode,
    pub fill: Fill,
    /// The trained team that plays the slots no client joined, instead of
    /// `fill`, when the server was started with one (`--fill ppo:DIR`: its
    /// spec). 1.2; absent otherwise.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fill_team: Option<String>,
    pub seed: u64,
    /// Control ticks per second of game time.
    pub control_hz: f32,
    /// Ticks played so far, and in the whole match.
    pub tick: Tick,
    pub total_ticks: u64,
    /// Lockstep deadline per tick in milliseconds.
    pub deadline_ms: u64,
    pub start_players: u8,
    pub score: Score,
    /// Which players of each team a client controls.
    pub taken: PerTeam<[bool; PLAYERS_PER_TEAM]>,
    /// The scenario the match started from (`create_match`'s `scenario`;
    /// protocol 1.5); absent for a match started from the kick-off.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub scenario: Option<ScenarioInfo>,
}

/// A match's scenario, as its description names it (protocol 1.5).
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct ScenarioInfo {
    /// The file's `name` (`"scenario"` when it has none).
    pub name: String,
    /// The colour the scenario's own team plays.
    pub team: Team,
}

/// How a match's scenario play ended, in its `match_end` (protocol 1.5).
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct ScenarioEnd {
    pub name: String,
    pub team: Team,
    /// The end condition that ended the play (its `when`, such as
    /// `goal_for`, or `time_up`); `None` when the match ended otherwise
    /// (an admin, the server stopping, a failure).
    pub ending: Option<String>,
    /// The outcome the file gives that condition; `None` with `ending`.
    pub success: Option<bool>,
    /// Control ticks played from the scenario's start.
    pub ticks: u64,
}

/// The join was accepted; observations follow.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Joined {
    pub match_id: MatchId,
    pub team: Team,
    pub players: Vec<Player>,
    /// The match seed: built-in policies derive their own streams from it.
    pub seed: u64,
    pub mode: Mode,
    pub control_hz: f32,
    pub total_ticks: u64,
    pub deadline_ms: u64,
    /// The pitch and the ball-control rule of this match, so a client needs
    /// no copy of the server's match configuration. Protocol 1.2; absent
    /// from older servers.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pitch: Option<Pitch>,
}

/// A match's pitch, from the server's match configuration (protocol 1.2).
/// Lengths in metres, angles in radians.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Pitch {
    /// Between the goal lines (x): the goal lines are at x = +-length/2.
    pub field_length: f32,
    /// Between the touch lines (y).
    pub field_width: f32,
    /// The goal mouth, between the inner edges of the posts (centred on y = 0).
    pub goal_width: f32,
    /// How far the goal reaches behind its line.
    pub goal_depth: f32,
    /// The underside of the crossbar above the ground.
    pub goal_height: f32,
    pub ball_radius: f32,
    /// The paper's `b_d`: a robot controls the ball only when it is closer
    /// than this to its torso...
    pub b_d: f32,
    /// ...and within this angle of its heading (the paper's `b_rad`).
    pub b_rad: f32,
    /// How observations place things: see [`Frame`].
    pub frame: Frame,
}

/// The frame observations are given in.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Frame {
    /// Each team sees the pitch in its own frame: origin at the centre
    /// spot, +x toward the opponent goal, +y to the left facing +x, z up;
    /// heading 0 faces +x and grows counter-clockwise, in (-pi, pi]. Blue's
    /// frame is the world frame (events use it); red's is turned half round.
    Team,
    /// A convention from a newer protocol version.
    #[serde(other)]
    Unknown,
}

/// Pushed once per tick to every joined client: one observation per player
/// it controls, in the order of its `join`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ObservationMsg {
    pub match_id: MatchId,
    pub tick: Tick,
    pub observations: Vec<Observation>,
    /// What the referee saw happen on the tick that led here (`tick - 1`),
    /// each event with the tick it happened on, in the order of
    /// `Match::step`; empty in a match's first observation. Protocol 1.2;
    /// absent from older servers.
    #[serde(default)]
    pub events: Vec<Event>,
}

/// [`ObservationMsg`] borrowing its observations, so the server encodes each
/// tick without allocating. Encodes exactly like `ServerMsg::Observation`.
#[derive(Debug, Clone, Copy, Serialize)]
#[serde(tag = "type", rename = "observation")]
pub struct ObservationRef<'a> {
    pub match_id: MatchId,
    pub tick: Tick,
    pub observations: &'a [Observation],
    pub events: &'a [Event],
}

/// Why a match ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum EndReason {
    /// The clock ran out.
    Finished,
    /// The server is shutting down.
    Shutdown,
    /// The match failed inside the server (a bug); an `internal` error
    /// follows. The server and its other matches go on.
    Internal,
    /// An admin ended it early (`end_match`; protocol 1.2). A client that
    /// said a minor version below 2 in its `hello` is told `shutdown`.
    Ended,
}

/// Pushed once when the match ends, to every client still joined; after it
/// the connection is back in the lobby (it may join again).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MatchEnd {
    pub match_id: MatchId,
    pub reason: EndReason,
    /// Ticks played.
    pub tick: Tick,
    pub score: Score,
    pub stats: MatchStats,
    /// Ticks on which a joined robot had no action in time (it stayed).
    pub misses: PerTeam<[u64; PLAYERS_PER_TEAM]>,
    /// Each robot's reward for the last tick played, which no observation
    /// follows (as `Observation::reward`). Protocol 1.1; read as 0 from 1.0.
    #[serde(default)]
    pub rewards: PerTeam<[f32; PLAYERS_PER_TEAM]>,
    /// The events of the last tick played when no observation followed it
    /// (as `ObservationMsg::events`), so the events a client receives add
    /// up to the match's. Protocol 1.2; absent from older servers.
    #[serde(default)]
    pub events: Vec<Event>,
    /// The referee's hash of the final state, 16 hex digits: equal for equal
    /// matches on one build (a string because JSON readers lose u64 precision).
    pub state_hash: String,
    /// For a match started from a scenario, how its play ended (protocol
    /// 1.5); absent otherwise. Boxed: a match ends once, and every other
    /// server message would otherwise be as large.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub scenario: Option<Box<ScenarioEnd>>,
}

#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Left {
    pub match_id: MatchId,
}

#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Pong {
    pub nonce: u64,
}
