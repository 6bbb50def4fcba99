//! Protocol messages. Every frame carries one JSON object whose `type` field
//! names the message; serde dispatches on it (internally tagged enums).
//!
//! Requests (client to server) each get exactly one reply, in order: a result
//! message or an [`ErrorMsg`]. Once a join is accepted, the server also
//! *pushes* [`ObservationMsg`] every tick and one [`MatchEnd`]; the client
//! answers observations with [`ActionMsg`], which gets no reply unless it is
//! rejected (the error then says `"in_reply_to": "action"`). See
//! docs/PROTOCOL.md for the full rules.
//!
//! Forward compatibility: unknown fields are ignored everywhere, and an
//! unknown `type` deserialises to the `Unknown` variant so that the receiver
//! can answer it (server) or skip it (client) instead of failing.

use crate::head::Member;
use crate::types::{Action, Event, MatchStats, Observation, Team, Tick, PLAYERS_PER_TEAM};
// Defined beside the other ids and per-team types; named here too, where
// the messages that carry them are.
pub use crate::types::{PerTeam, Player, Score};
use serde::{Deserialize, Serialize};
use std::fmt;

/// Protocol name sent in `hello` and `welcome`.
pub const PROTOCOL_NAME: &str = "naosoccer";

/// This build's protocol version. Peers must agree on `major`; a higher
/// `minor` only adds optional fields and message types.
pub const PROTOCOL_VERSION: Version = Version { major: 1, minor: 4 };

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct Version {
    pub major: u32,
    pub minor: u32,
}

impl fmt::Display for Version {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}.{}", self.major, self.minor)
    }
}

/// A match on a server; assigned by the server, counting from 1.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
#[serde(transparent)]
pub struct MatchId(pub u64);

impl fmt::Display for MatchId {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.0)
    }
}

/// How a match advances.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum Mode {
    /// A tick advances when every joined robot has an action for it, or at
    /// the deadline (missing actions mean `stay` and are counted as misses).
    #[default]
    Lockstep,
    /// Ticks advance at the configured control rate; an action that arrives
    /// late applies at the next tick.
    Realtime,
}

impl fmt::Display for Mode {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Mode::Lockstep => "lockstep",
            Mode::Realtime => "realtime",
        })
    }
}

impl std::str::FromStr for Mode {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s {
            "lockstep" => Ok(Mode::Lockstep),
            "realtime" => Ok(Mode::Realtime),
            other => Err(format!(
                "unknown mode {other:?} (expected lockstep or realtime)"
            )),
        }
    }
}

/// Who plays the slots no client has joined. On the wire a string:
/// `"scripted"`, `"idle"`, or `"scripted:1"` ... `"scripted:5"`, a level of
/// the ladder of built-in teams (weakest first; `"scripted:3"` plays as
/// `"scripted"`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(try_from = "String", into = "String")]
pub enum Fill {
    /// The built-in scripted policy.
    #[default]
    Scripted,
    /// The robot stands still.
    Idle,
    /// A level of the scripted ladder, 1..=[`SCRIPTED_LEVELS`]. A match
    /// reports it as `fill: "scripted"` with `fill_team: "scripted:N"`, so
    /// clients that know only the first two values read every match.
    ScriptedLevel(u8),
}

/// Levels of the scripted ladder (`Fill::ScriptedLevel`).
pub const SCRIPTED_LEVELS: u8 = 5;

impl std::str::FromStr for Fill {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s {
            "scripted" => Ok(Fill::Scripted),
            "idle" => Ok(Fill::Idle),
            other => other
                .strip_prefix("scripted:")
                .and_then(|n| n.parse::<u8>().ok())
                .filter(|n| (1..=SCRIPTED_LEVELS).contains(n))
                .map(Fill::ScriptedLevel)
                .ok_or_else(|| {
                    format!(
                        "unknown fill {other:?} (expected scripted, scripted:1 to \
                         scripted:{SCRIPTED_LEVELS} or idle)"
                    )
                }),
        }
    }
}

impl fmt::Display for Fill {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Fill::Scripted => f.write_str("scripted"),
            Fill::Idle => f.write_str("idle"),
            Fill::ScriptedLevel(n) => write!(f, "scripted:{n}"),
        }
    }
}

impl TryFrom<String> for Fill {
    type Error = String;
    fn try_from(s: String) -> Result<Self, Self::Error> {
        s.parse()
    }
}

impl From<Fill> for String {
    fn from(f: Fill) -> String {
        f.to_string()
    }
}

// ---------------------------------------------------------------- client to server

/// Everything a client sends.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case")]
pub enum ClientMsg {
    Hello(Hello),
    CreateMatch(CreateMatch),
    ListMatches(ListMatches),
    Join(Join),
    Action(ActionMsg),
    Leave(Leave),
    Ping(Ping),
    EndMatch(EndMatch),
    /// A `type` this build does not know; answered with `unimplemented`.
    #[serde(other, skip_serializing)]
    Unknown,
}

impl ClientMsg {
    /// The wire names of the known `type`s.
    pub const KINDS: [&'static str; 8] = [
        "hello",
        "create_match",
        "list_matches",
        "join",
        "action",
        "leave",
        "ping",
        "end_match",
    ];

    /// Decodes one frame's payload. On failure, the error keeps what could
    /// be read of the frame (its `type`, an action's `tick`) for the reply.
    pub fn decode(payload: &[u8]) -> Result<ClientMsg, Undecodable> {
        serde_json::from_slice(payload).map_err(|error| Undecodable {
            head: FrameHead::peek(payload),
            error,
        })
    }

    /// The wire name of this message's `type`.
    pub fn kind(&self) -> &'static str {
        match self {
            ClientMsg::Hello(_) => "hello",
            ClientMsg::CreateMatch(_) => "create_match",
            ClientMsg::ListMatches(_) => "list_matches",
            ClientMsg::Join(_) => "join",
            ClientMsg::Action(_) => "action",
            ClientMsg::Leave(_) => "leave",
            ClientMsg::Ping(_) => "ping",
            ClientMsg::EndMatch(_) => "end_match",
            ClientMsg::Unknown => "unknown",
        }
    }
}

/// What a server can read of a client frame besides its full decoding: the
/// `type` (as [`ClientMsg::kind`] names it) and, for an action, its `tick`.
/// An error answering the frame carries both (`in_reply_to`, `tick`), so the
/// client can pair it even when a field failed to decode (issue 15).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct FrameHead {
    /// `None` when the payload is not a JSON object with a string `type`;
    /// `"unknown"` for a type this build does not know.
    pub kind: Option<&'static str>,
    /// The `tick` of an `action`, when it holds a valid tick number.
    pub tick: Option<Tick>,
}

impl FrameHead {
    /// Reads the head of a payload leniently: other fields may be missing
    /// or ill-typed, and nested deeper than serde_json parses (the frame is
    /// read without recursion, in time linear in its length). For error
    /// paths only.
    pub fn peek(payload: &[u8]) -> FrameHead {
        let Some(top) = crate::head::top_level(payload) else {
            return FrameHead::default();
        };
        fn scalar(m: Option<Member<'_>>) -> Option<&[u8]> {
            match m {
                Some(Member::Scalar(text)) => Some(text),
                _ => None,
            }
        }
        let Some(kind) = scalar(top.ty).and_then(|t| serde_json::from_slice::<String>(t).ok())
        else {
            return FrameHead::default();
        };
        let kind = ClientMsg::KINDS
            .iter()
            .copied()
            .find(|k| *k == kind)
            .unwrap_or("unknown");
        let tick = (kind == "action")
            .then(|| {
                let t = serde_json::from_slice::<serde_json::Value>(scalar(top.tick)?).ok()?;
                t.as_u64().map(Tick::new)
            })
            .flatten();
        FrameHead {
            kind: Some(kind),
            tick,
        }
    }

    /// An error answering this frame: `in_reply_to` and `tick` as read.
    pub fn error(self, code: ErrorCode, message: impl Into<String>) -> ErrorMsg {
        ErrorMsg {
            in_reply_to: self.kind.map(str::to_owned),
            tick: self.tick,
            ..ErrorMsg::new(code, message)
        }
    }
}

/// A client frame that did not decode as a [`ClientMsg`].
#[derive(Debug)]
pub struct Undecodable {
    /// What could be read of it.
    pub head: FrameHead,
    pub error: serde_json::Error,
}

impl Undecodable {
    /// The `invalid_argument` error answering the frame.
    pub fn to_error(&self) -> ErrorMsg {
        self.head.error(
            ErrorCode::InvalidArgument,
            format!("not a valid message: {}", self.error),
        )
    }
}

/// The first message on every connection.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Hello {
    /// Must be `"naosoccer"`.
    pub protocol: String,
    pub version: Version,
    /// Free text for the server's logs.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub client: Option<String>,
}

impl Hello {
    pub fn new(client: impl Into<String>) -> Hello {
        Hello {
            protocol: PROTOCOL_NAME.to_owned(),
            version: PROTOCOL_VERSION,
            client: Some(client.into()),
        }
    }
}

/// Create a match (admin token). Every field but the token is optional and
/// defaults to the server's configuration.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default)]
pub struct CreateMatch {
    pub token: String,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub seed: Option<u64>,
    /// Match length in minutes of game time (a finite number: a value that
    /// overflows `f32`, such as `1e300`, is refused at decoding).
    #[serde(
        default,
        skip_serializing_if = "Option::is_none",
        deserialize_with = "finite_f32"
    )]
    pub minutes: Option<f32>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mode: Option<Mode>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fill: Option<Fill>,
    /// Robots that must be joined before the first tick (0..=8).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub start_players: Option<u8>,
    /// Lockstep: how long a tick waits for actions, in milliseconds.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub deadline_ms: Option<u64>,
}

#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize, Default)]
pub struct ListMatches {}

/// Take control of one or more players of one team.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Join {
    /// Omitted: the oldest unfinished match where all requested slots are free.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub match_id: Option<MatchId>,
    pub team: Team,
    pub token: String,
    /// One player: a robot client. Several: a team client.
    pub players: Vec<Player>,
}

/// One player's action.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct PlayerAction {
    pub player: Player,
    pub action: Action,
}

/// The answer to an observation: actions for (some of) the client's players.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct ActionMsg {
    /// The tick of the observation being answered.
    pub tick: Tick,
    /// If present, must be the joined team.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub team: Option<Team>,
    pub actions: Vec<PlayerAction>,
}

/// [`ActionMsg`] borrowing its actions, so a client can send one per tick
/// without allocating. Encodes exactly like `ClientMsg::Action`.
#[derive(Debug, Clone, Copy, Serialize)]
#[serde(tag = "type", rename = "action")]
pub struct ActionRef<'a> {
    pub tick: Tick,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub team: Option<Team>,
    pub actions: &'a [PlayerAction],
}

#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize, Default)]
pub struct Leave {}

/// End a match early (admin token; protocol 1.2): every client of the
/// match gets its `match_end` (reason `ended`), then the reply
/// [`MatchEnded`] comes.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct EndMatch {
    pub token: String,
    pub match_id: MatchId,
}

#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize, Default)]
pub struct Ping {
    /// Echoed in the `pong`.
    #[serde(default)]
    pub nonce: u64,
}

// ---------------------------------------------------------------- server to client

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
}

#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Left {
    pub match_id: MatchId,
}

#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Pong {
    pub nonce: u64,
}

/// Stable error codes (the gRPC canonical names, in snake case).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ErrorCode {
    /// Malformed JSON, a missing or ill-typed field, a value out of range.
    InvalidArgument,
    /// The request is valid but not in this state: before `hello`, joining
    /// twice, a slot already taken, acting without a join, a finished match.
    FailedPrecondition,
    /// No such match.
    NotFound,
    /// Wrong token, or acting for a player the connection does not control.
    PermissionDenied,
    /// Unknown message type, or an unsupported protocol major version.
    Unimplemented,
    /// A frame over the cap, or the server is at its connection/match limit.
    ResourceExhausted,
    /// An action arrived after its tick was played (lockstep).
    DeadlineExceeded,
    /// The server is shutting down.
    Unavailable,
    /// A bug in the server.
    Internal,
    /// A code from a newer protocol version.
    #[serde(other)]
    Unknown,
}

impl ErrorCode {
    pub fn as_str(self) -> &'static str {
        match self {
            ErrorCode::InvalidArgument => "invalid_argument",
            ErrorCode::FailedPrecondition => "failed_precondition",
            ErrorCode::NotFound => "not_found",
            ErrorCode::PermissionDenied => "permission_denied",
            ErrorCode::Unimplemented => "unimplemented",
            ErrorCode::ResourceExhausted => "resource_exhausted",
            ErrorCode::DeadlineExceeded => "deadline_exceeded",
            ErrorCode::Unavailable => "unavailable",
            ErrorCode::Internal => "internal",
            ErrorCode::Unknown => "unknown",
        }
    }
}

impl fmt::Display for ErrorCode {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

/// The error reply. `fatal: true` means the server closes the connection
/// right after sending it.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct ErrorMsg {
    pub code: ErrorCode,
    pub message: String,
    pub fatal: bool,
    /// The `type` of the message this answers, when known.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub in_reply_to: Option<String>,
    /// For rejected actions: the tick the action named.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tick: Option<Tick>,
}

impl ErrorMsg {
    pub fn new(code: ErrorCode, message: impl Into<String>) -> ErrorMsg {
        ErrorMsg {
            code,
            message: message.into(),
            fatal: false,
            in_reply_to: None,
            tick: None,
        }
    }
    pub fn fatal(mut self) -> ErrorMsg {
        self.fatal = true;
        self
    }
    pub fn in_reply_to(mut self, kind: &str) -> ErrorMsg {
        self.in_reply_to = Some(kind.to_owned());
        self
    }
}

impl fmt::Display for ErrorMsg {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}: {}", self.code, self.message)?;
        if self.fatal {
            f.write_str(" (fatal)")?;
        }
        Ok(())
    }
}

impl std::error::Error for ErrorMsg {}

impl From<ErrorMsg> for ServerMsg {
    fn from(e: ErrorMsg) -> ServerMsg {
        ServerMsg::Error(e)
    }
}

/// An optional `f32` that must be finite: JSON numbers too large for `f32`
/// parse to infinity, which would encode back as `null` (issue 15: the fuzz
/// target's round trip).
fn finite_f32<'de, D: serde::Deserializer<'de>>(d: D) -> Result<Option<f32>, D::Error> {
    let v = Option::<f32>::deserialize(d)?;
    match v {
        Some(x) if !x.is_finite() => Err(serde::de::Error::custom(format!(
            "expected a finite number, got {x}"
        ))),
        v => Ok(v),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::types::{BallObs, RobotObs, ScoreObs};

    #[test]
    fn fills_are_strings_on_the_wire_levels_included() {
        for (fill, text) in [
            (Fill::Scripted, "scripted"),
            (Fill::Idle, "idle"),
            (Fill::ScriptedLevel(1), "scripted:1"),
            (Fill::ScriptedLevel(5), "scripted:5"),
        ] {
            assert_eq!(serde_json::to_value(fill).unwrap(), text);
            assert_eq!(serde_json::from_value::<Fill>(text.into()).unwrap(), fill);
            assert_eq!(text.parse::<Fill>(), Ok(fill));
        }
        for bad in [
            "scripted:0",
            "scripted:6",
            "scripted:x",
            "scripted:",
            "level",
        ] {
            let e = serde_json::from_value::<Fill>(bad.into()).unwrap_err();
            assert!(e.to_string().contains("unknown fill"), "{bad}: {e}");
        }
        let req: CreateMatch =
            serde_json::from_str(r#"{"token": "t", "fill": "scripted:4"}"#).unwrap();
        assert_eq!(req.fill, Some(Fill::ScriptedLevel(4)));
    }

    fn obs(player: u8) -> Observation {
        Observation {
            tick: Tick::new(7),
            team: Team::Red,
            player: Player::new(player as usize).unwrap(),
            time_left: 599.3,
            score: ScoreObs {
                own: 1,
                opponent: 2,
            },
            own: [RobotObs {
                x: -1.5,
                y: 0.25,
                heading: 0.1,
                fallen: false,
                busy: true,
            }; 4],
            opponents: [RobotObs {
                x: 1.0,
                y: -0.3,
                heading: 3.1,
                fallen: true,
                busy: false,
            }; 4],
            ball: BallObs {
                x: 0.123_456_79,
                y: -2.0e-7,
                vx: 0.0,
                vy: 1.5,
            },
            control: [false, true, false, false],
            opponent_control: false,
            reward: 0.0,
            half: 2,
            set_play: Some(crate::types::SetPlayObs {
                kind: crate::types::SetPlayKind::CornerKick,
                own: false,
                ticks_left: 120,
            }),
        }
    }

    #[test]
    fn borrowed_forms_encode_like_owned() {
        let observations = vec![obs(0), obs(3)];
        let events = vec![
            crate::types::Event::Kick {
                tick: Tick::new(6),
                robot: crate::types::RobotId::new(Team::Red, 2).unwrap(),
                speed: 2.5,
            },
            crate::types::Event::HalfTime { tick: Tick::new(6) },
        ];
        let owned = ServerMsg::Observation(ObservationMsg {
            match_id: MatchId(4),
            tick: Tick::new(7),
            observations: observations.clone(),
            events: events.clone(),
        });
        let borrowed = ObservationRef {
            match_id: MatchId(4),
            tick: Tick::new(7),
            observations: &observations,
            events: &events,
        };
        assert_eq!(
            serde_json::to_string(&owned).unwrap(),
            serde_json::to_string(&borrowed).unwrap()
        );
        let back: ServerMsg =
            serde_json::from_str(&serde_json::to_string(&borrowed).unwrap()).unwrap();
        assert_eq!(back, owned);

        let actions = vec![PlayerAction {
            player: Player::new(2).unwrap(),
            action: Action::TurnLeft,
        }];
        let owned = ClientMsg::Action(ActionMsg {
            tick: Tick::new(3),
            team: None,
            actions: actions.clone(),
        });
        let borrowed = ActionRef {
            tick: Tick::new(3),
            team: None,
            actions: &actions,
        };
        assert_eq!(
            serde_json::to_string(&owned).unwrap(),
            serde_json::to_string(&borrowed).unwrap()
        );
    }

    #[test]
    fn unknown_types_and_fields() {
        let m: ClientMsg = serde_json::from_str(r#"{"type":"teleport","x":1}"#).unwrap();
        assert_eq!(m, ClientMsg::Unknown);
        let m: ClientMsg =
            serde_json::from_str(r#"{"nonce":5,"type":"ping","extra":[1,2]}"#).unwrap();
        assert_eq!(m, ClientMsg::Ping(Ping { nonce: 5 }));
        let m: ClientMsg = serde_json::from_str(r#"{"type":"list_matches","x":{}}"#).unwrap();
        assert_eq!(m, ClientMsg::ListMatches(ListMatches {}));
        let m: ServerMsg = serde_json::from_str(r#"{"type":"weather","rain":true}"#).unwrap();
        assert_eq!(m, ServerMsg::Unknown);
        let e: ErrorMsg =
            serde_json::from_str(r#"{"code":"quota","message":"m","fatal":false}"#).unwrap();
        assert_eq!(e.code, ErrorCode::Unknown);
    }

    /// Issue 15: a later server's new event kind does not break a 1.2
    /// client's observation; the known events around it stay.
    #[test]
    fn unknown_event_kinds_are_read_as_unknown() {
        let owned = ServerMsg::Observation(ObservationMsg {
            match_id: MatchId(4),
            tick: Tick::new(7),
            observations: vec![obs(1)],
            events: vec![
                crate::types::Event::HalfTime { tick: Tick::new(5) },
                crate::types::Event::End { tick: Tick::new(6) },
            ],
        });
        let mut v = serde_json::to_value(&owned).unwrap();
        v["events"].as_array_mut().unwrap().insert(
            1,
            serde_json::json!({"kind": "drop_ball", "tick": 6, "x": 1.5}),
        );
        let back: ServerMsg = serde_json::from_value(v).unwrap();
        let ServerMsg::Observation(o) = back else {
            panic!("{back:?}")
        };
        use crate::types::Event;
        assert_eq!(
            o.events,
            [
                Event::HalfTime { tick: Tick::new(5) },
                Event::Unknown,
                Event::End { tick: Tick::new(6) }
            ]
        );
        assert_eq!(o.events[1].tick(), None);
        assert_eq!(o.observations, vec![obs(1)]);
        // A known kind with a bad field is still an error, not `Unknown`.
        assert!(serde_json::from_str::<Event>(r#"{"kind":"end","tick":"x"}"#).is_err());
    }

    #[test]
    fn player_numbers_validated() {
        assert!(serde_json::from_str::<Player>("3").is_ok());
        assert!(serde_json::from_str::<Player>("4").is_err());
        let bad = r#"{"type":"join","team":"blue","token":"t","players":[0,9]}"#;
        assert!(serde_json::from_str::<ClientMsg>(bad).is_err());
    }

    #[test]
    fn f32_fields_round_trip_exactly() {
        // Observations cross the socket as JSON; the end-to-end test relies on
        // the client seeing the very same f32 values the referee produced.
        let mut x = 1.0e-6f32;
        while x < 1.0e4 {
            for v in [x, -x, x * 1.000_001, x.next_up_compat()] {
                let s = serde_json::to_string(&v).unwrap();
                let back: f32 = serde_json::from_str(&s).unwrap();
                assert_eq!(back.to_bits(), v.to_bits(), "{v} -> {s}");
            }
            x *= 1.37;
        }
    }

    #[test]
    fn f64_statistics_round_trip_exactly() {
        for (a, b) in [
            (20u32, 22u32),
            (1, 3),
            (10, 11),
            (2, 22),
            (5999, 6000),
            (1, 7),
        ] {
            let v = f64::from(a) / f64::from(b);
            let back: f64 = serde_json::from_str(&serde_json::to_string(&v).unwrap()).unwrap();
            assert_eq!(back.to_bits(), v.to_bits(), "{a}/{b}");
        }
    }

    trait NextUp {
        fn next_up_compat(self) -> Self;
    }
    impl NextUp for f32 {
        fn next_up_compat(self) -> f32 {
            f32::from_bits(self.to_bits() + 1)
        }
    }

    /// Issue 15 A.1: a frame whose `type` could be read keeps it, and an
    /// action its tick, when another field fails to decode.
    #[test]
    fn issue_15_undecodable_frames_keep_their_type_and_tick() {
        let cases = [
            (
                r#"{"type":"action","tick":4,"actions":[{"player":0,"action":"dance"}]}"#,
                Some("action"),
                Some(Tick::new(4)),
            ),
            (
                r#"{"type":"action","tick":4,"actions":[{"player":9,"action":"stay"}]}"#,
                Some("action"),
                Some(Tick::new(4)),
            ),
            (
                r#"{"type":"action","tick":4,"team":"green","actions":[]}"#,
                Some("action"),
                Some(Tick::new(4)),
            ),
            (
                r#"{"type":"action","tick":-1,"actions":[]}"#,
                Some("action"),
                None,
            ),
            (
                r#"{"type":"action","tick":"4","actions":[]}"#,
                Some("action"),
                None,
            ),
            (r#"{"type":"action","actions":[]}"#, Some("action"), None),
            (
                r#"{"type":"create_match","token":"a","mode":"fast"}"#,
                Some("create_match"),
                None,
            ),
            (
                r#"{"type":"join","team":"green","token":"t","players":[0]}"#,
                Some("join"),
                None,
            ),
            (r#"{"type":"ping","nonce":"17"}"#, Some("ping"), None),
            (r#"{"type":"hello"}"#, Some("hello"), None),
            (r#"{"type":"leave","tick":3,"x":[}"#, None, None),
            (r#"[1,2]"#, None, None),
            (r#""ping""#, None, None),
            (r#"{"nonce":3}"#, None, None),
            (r#"{"type":"ping","#, None, None),
        ];
        for (payload, kind, tick) in cases {
            let e = ClientMsg::decode(payload.as_bytes())
                .unwrap_err()
                .to_error();
            assert_eq!(e.code, ErrorCode::InvalidArgument, "{payload}");
            assert!(!e.fatal, "{payload}");
            assert_eq!(e.in_reply_to.as_deref(), kind, "{payload}");
            assert_eq!(e.tick, tick, "{payload}");
        }
        // A frame refused before decoding (over the rate) is read the same way.
        let head = FrameHead::peek(br#"{"type":"teleport","tick":2}"#);
        assert_eq!((head.kind, head.tick), (Some("unknown"), None));
        for msg in [
            ClientMsg::ListMatches(ListMatches {}),
            ClientMsg::Leave(Leave {}),
            ClientMsg::Ping(Ping { nonce: 3 }),
            ClientMsg::EndMatch(EndMatch {
                token: "t".into(),
                match_id: MatchId(2),
            }),
            ClientMsg::CreateMatch(CreateMatch::default()),
            ClientMsg::Hello(Hello::new("x")),
            ClientMsg::Action(ActionMsg {
                tick: Tick::new(9),
                team: None,
                actions: vec![],
            }),
            ClientMsg::Join(Join {
                match_id: None,
                team: Team::Red,
                token: "t".into(),
                players: vec![],
            }),
        ] {
            let bytes = serde_json::to_vec(&msg).unwrap();
            let head = FrameHead::peek(&bytes);
            assert_eq!(head.kind, Some(msg.kind()));
            assert!(ClientMsg::KINDS.contains(&msg.kind()));
            assert_eq!(
                head.tick,
                matches!(msg, ClientMsg::Action(_)).then_some(Tick::new(9))
            );
        }
    }

    /// docs/PROTOCOL.md, section 1: 127 levels of nesting decode (unknown
    /// fields are ignored), 128 are refused; the error names the `type`
    /// however deep the frame (issue 39).
    #[test]
    fn nesting_past_127_levels_is_refused_with_its_type() {
        let nested = |levels: usize| {
            let inner = levels - 1; // the message's own object is one
            format!(
                r#"{{"type":"ping","nonce":4,"x":{}{}}}"#,
                "[".repeat(inner),
                "]".repeat(inner)
            )
        };
        let ok = ClientMsg::decode(nested(127).as_bytes()).unwrap();
        assert_eq!(ok, ClientMsg::Ping(Ping { nonce: 4 }));
        for levels in [128, 30_000] {
            let e = ClientMsg::decode(nested(levels).as_bytes())
                .unwrap_err()
                .to_error();
            assert_eq!(e.code, ErrorCode::InvalidArgument);
            assert_eq!(e.in_reply_to.as_deref(), Some("ping"), "{levels} levels");
        }
    }

    /// Protocol 1.2's fields are optional: messages from a 1.1 server read
    /// without them, and a frame convention from a newer one reads as
    /// unknown instead of failing.
    #[test]
    fn protocol_1_2_fields_are_optional() {
        let j: ServerMsg = serde_json::from_str(
            r#"{"type":"joined","match_id":1,"team":"red","players":[2],"seed":3,"mode":"lockstep","control_hz":10.0,"total_ticks":60,"deadline_ms":100}"#,
        )
        .unwrap();
        assert!(matches!(j, ServerMsg::Joined(Joined { pitch: None, .. })));
        let p: Pitch = serde_json::from_str(
            r#"{"field_length":6,"field_width":4.5,"goal_width":2.6,"goal_depth":1,"goal_height":0.8,"ball_radius":0.05,"b_d":0.3,"b_rad":0.4,"frame":"polar"}"#,
        )
        .unwrap();
        assert_eq!(p.frame, Frame::Unknown);
        let o: ServerMsg = serde_json::from_str(
            r#"{"type":"observation","match_id":1,"tick":0,"observations":[]}"#,
        )
        .unwrap();
        assert!(
            matches!(o, ServerMsg::Observation(ObservationMsg { events, .. }) if events.is_empty())
        );
        let e: ClientMsg =
            serde_json::from_str(r#"{"type":"end_match","token":"t","match_id":4}"#).unwrap();
        assert_eq!(e.kind(), "end_match");
        assert!(ClientMsg::decode(br#"{"type":"end_match","token":"t"}"#).is_err());
    }

    /// Issue 15: a number too large for f32 parsed to infinity, which
    /// encodes as null; it is refused at decoding now.
    #[test]
    fn issue_15_non_finite_minutes_are_refused() {
        let bad = r#"{"type":"create_match","token":"a","minutes":200000000001576e204}"#;
        let err = serde_json::from_str::<ClientMsg>(bad).unwrap_err();
        assert!(err.to_string().contains("finite"), "{err}");
        let ok: ClientMsg =
            serde_json::from_str(r#"{"type":"create_match","token":"a","minutes":2.5}"#).unwrap();
        let back: ClientMsg = serde_json::from_str(&serde_json::to_string(&ok).unwrap()).unwrap();
        assert_eq!(ok, back);
        let none: ClientMsg =
            serde_json::from_str(r#"{"type":"create_match","token":"a"}"#).unwrap();
        assert!(matches!(
            none,
            ClientMsg::CreateMatch(CreateMatch { minutes: None, .. })
        ));
    }
}
