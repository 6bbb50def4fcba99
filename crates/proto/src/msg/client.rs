//! Client to server: the requests, the actions, and what a server reads of
//! a frame that does not decode.

use serde::{Deserialize, Serialize};

use super::{
    ErrorCode, ErrorMsg, Fill, MatchId, Mode, Player, Version, PROTOCOL_NAME, PROTOCOL_VERSION,
};
use crate::head::Member;
use crate::types::{Action, BallPlacement, RobotPlacement, StateChange, Team, Tick};

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
    SetState(SetState),
    /// A `type` this build does not know; answered with `unimplemented`.
    #[serde(other, skip_serializing)]
    Unknown,
}

impl ClientMsg {
    /// The wire names of the known `type`s.
    pub const KINDS: [&'static str; 9] = [
        "hello",
        "create_match",
        "list_matches",
        "join",
        "action",
        "leave",
        "ping",
        "end_match",
        "set_state",
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
            ClientMsg::SetState(_) => "set_state",
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
    /// A scenario file's text (TOML, docs/SCENARIOS.md): the match starts
    /// from it and ends when its play ends (protocol 1.5).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub scenario: Option<String>,
    /// The colour the scenario's own team plays (default blue; only with
    /// `scenario`; protocol 1.5).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub scenario_team: Option<Team>,
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
/// [`MatchEnded`](super::MatchEnded) comes.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct EndMatch {
    pub token: String,
    pub match_id: MatchId,
}

/// Set the state of a running match (admin token; protocol 1.5): move the
/// ball and any robots, as rcssserver's trainer does. Answered by
/// [`StateSet`](super::StateSet). World coordinates.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SetState {
    pub token: String,
    pub match_id: MatchId,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ball: Option<BallPlacement>,
    /// Left out or `null`: no robot.
    #[serde(
        default,
        skip_serializing_if = "Vec::is_empty",
        deserialize_with = "crate::types::null_as_default"
    )]
    pub robots: Vec<RobotPlacement>,
}

impl SetState {
    /// The change it asks for.
    pub fn change(&self) -> StateChange {
        StateChange {
            ball: self.ball,
            robots: self.robots.clone(),
        }
    }
}

#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize, Default)]
pub struct Ping {
    /// Echoed in the `pong`.
    #[serde(default)]
    pub nonce: u64,
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
