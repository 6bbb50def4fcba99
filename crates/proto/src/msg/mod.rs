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
//!
//! The messages live in three files, all re-exported here: `client.rs`
//! (everything a client sends), `server.rs` (everything a server sends but
//! errors) and `error.rs` (the error reply); this one holds what both
//! directions share (the protocol version, match ids, modes, fills).

// Defined beside the other ids and per-team types; named here too, where
// the messages that carry them are.
pub use crate::types::{PerTeam, Player, Score};
use serde::{Deserialize, Serialize};
use std::fmt;

mod client;
mod error;
mod server;

pub use client::*;
pub use error::*;
pub use server::*;

/// Protocol name sent in `hello` and `welcome`.
pub const PROTOCOL_NAME: &str = "naosoccer";

/// This build's protocol version. Peers must agree on `major`; a higher
/// `minor` only adds optional fields and message types.
pub const PROTOCOL_VERSION: Version = Version { major: 1, minor: 6 };

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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::types::{Action, BallObs, Observation, RobotObs, ScoreObs, Team, Tick};

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
                receiver: crate::types::RobotId::new(Team::Red, 3),
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

    /// Protocol 1.5: `set_state` and its reply, the `state_set` event, and
    /// `scenario` in `create_match`, descriptions and `match_end`, all
    /// optional where a 1.4 peer leaves them out.
    #[test]
    fn protocol_1_5_messages_and_fields() {
        let m: ClientMsg = serde_json::from_str(
            r#"{"type":"set_state","token":"t","match_id":2,"robots":[{"robot":9,"x":0.5,"y":-1}]}"#,
        )
        .unwrap();
        let ClientMsg::SetState(s) = &m else {
            panic!("{m:?}")
        };
        assert_eq!(m.kind(), "set_state");
        assert_eq!(s.ball, None);
        let r = s.robots[0];
        // Any unsigned robot number decodes; the referee names a bad one.
        assert_eq!((r.robot, r.heading, r.fallen), (9, None, false));
        assert_eq!(s.change().robots, s.robots);
        let null: ClientMsg = serde_json::from_str(
            r#"{"type":"set_state","token":"t","match_id":2,"ball":{"x":1,"y":2,"vx":null,"vy":null},"robots":null}"#,
        )
        .unwrap();
        assert!(
            matches!(null, ClientMsg::SetState(SetState { ref robots, .. }) if robots.is_empty())
        );
        for bad in [
            r#"{"type":"set_state","token":"t","ball":{"x":0,"y":0}}"#,
            r#"{"type":"set_state","token":"t","match_id":1,"ball":{"x":0}}"#,
            r#"{"type":"set_state","token":"t","match_id":1,"robots":[{"robot":-1,"x":0,"y":0}]}"#,
        ] {
            let e = ClientMsg::decode(bad.as_bytes()).unwrap_err().to_error();
            assert_eq!(e.in_reply_to.as_deref(), Some("set_state"), "{bad}");
        }
        let r: ServerMsg =
            serde_json::from_str(r#"{"type":"state_set","match_id":2,"tick":7}"#).unwrap();
        assert_eq!(
            r,
            ServerMsg::StateSet(StateSet {
                match_id: MatchId(2),
                tick: Tick::new(7)
            })
        );
        let e: crate::types::Event =
            serde_json::from_str(r#"{"kind":"state_set","tick":7}"#).unwrap();
        assert_eq!(e.tick(), Some(Tick::new(7)));
        let c: ClientMsg = serde_json::from_str(
            r#"{"type":"create_match","token":"a","scenario":"name = \"x\"\n","scenario_team":"red"}"#,
        )
        .unwrap();
        assert!(matches!(
            c,
            ClientMsg::CreateMatch(CreateMatch {
                scenario: Some(_),
                scenario_team: Some(Team::Red),
                ..
            })
        ));
        let info = r#"{"match_id":1,"state":"running","mode":"lockstep","fill":"idle","seed":1,"control_hz":10.0,"tick":3,"total_ticks":60,"deadline_ms":100,"start_players":1,"score":{"blue":0,"red":0},"taken":{"blue":[false,false,false,false],"red":[false,false,false,false]}}"#;
        let info: MatchInfo = serde_json::from_str(info).unwrap();
        assert_eq!(info.scenario, None);
        assert!(!serde_json::to_string(&info).unwrap().contains("scenario"));
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
