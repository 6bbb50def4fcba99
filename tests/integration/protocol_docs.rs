//! docs/PROTOCOL.md is the protocol's reference: every ```json block in it
//! must parse as the message its `type` names and encode back unchanged, the
//! framing example must be what the encoder produces, and every message type
//! must be documented.

use naosoccer_proto::frame;
use naosoccer_proto::msg::{ClientMsg, ServerMsg};
use serde_json::Value;

const DOC: &str = include_str!("../../docs/PROTOCOL.md");

const CLIENT_TYPES: &[&str] = &[
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
const SERVER_TYPES: &[&str] = &[
    "welcome",
    "match_created",
    "match_list",
    "joined",
    "observation",
    "match_end",
    "left",
    "pong",
    "match_ended",
    "state_set",
    "error",
];

/// `msg` as the JSON a peer receives (f32 fields in their shortest decimal
/// form, as the encoder writes them; `to_value` would widen them to f64).
fn reparse<T: serde::Serialize>(msg: &T) -> Value {
    serde_json::from_str(&serde_json::to_string(msg).unwrap()).unwrap()
}

/// The contents of every fenced block with this info string.
fn blocks(lang: &str) -> Vec<String> {
    let fence = format!("```{lang}");
    let mut out = Vec::new();
    let mut lines = DOC.lines();
    while let Some(line) = lines.next() {
        if line.trim_end() == fence {
            let body: Vec<&str> = lines
                .by_ref()
                .take_while(|l| l.trim_end() != "```")
                .collect();
            out.push(body.join("\n"));
        }
    }
    out
}

#[test]
fn every_json_example_round_trips() {
    let examples = blocks("json");
    assert!(
        examples.len() >= 16,
        "found only {} json blocks",
        examples.len()
    );
    let mut seen = Vec::new();
    for text in &examples {
        let value: Value =
            serde_json::from_str(text).unwrap_or_else(|e| panic!("not JSON ({e}):\n{text}"));
        let ty = value["type"]
            .as_str()
            .unwrap_or_else(|| panic!("no type:\n{text}"))
            .to_owned();
        let back = if CLIENT_TYPES.contains(&ty.as_str()) {
            let msg: ClientMsg =
                serde_json::from_value(value.clone()).unwrap_or_else(|e| panic!("{ty}: {e}"));
            assert_ne!(msg, ClientMsg::Unknown, "{ty}");
            let again: ClientMsg =
                serde_json::from_str(&serde_json::to_string(&msg).unwrap()).unwrap();
            assert_eq!(again, msg);
            reparse(&msg)
        } else {
            let msg: ServerMsg =
                serde_json::from_value(value.clone()).unwrap_or_else(|e| panic!("{ty}: {e}"));
            assert_ne!(msg, ServerMsg::Unknown, "{ty}");
            let again: ServerMsg =
                serde_json::from_str(&serde_json::to_string(&msg).unwrap()).unwrap();
            assert_eq!(again, msg);
            reparse(&msg)
        };
        assert_eq!(
            back, value,
            "{ty} does not encode back to the documented JSON"
        );
        seen.push(ty);
    }
    for ty in CLIENT_TYPES.iter().chain(SERVER_TYPES) {
        assert!(
            seen.iter().any(|s| s == ty),
            "no example of {ty} in docs/PROTOCOL.md"
        );
    }
}

#[test]
fn framing_example_matches_the_encoder() {
    let text = blocks("text")
        .into_iter()
        .next()
        .expect("a ```text block with the frame bytes");
    let hex_line = text.lines().next().unwrap();
    let documented: Vec<u8> = hex_line
        .split_whitespace()
        .map(|h| u8::from_str_radix(h, 16).unwrap())
        .collect();
    let encoded = frame::encode(&serde_json::json!({"type": "ping"})).unwrap();
    assert_eq!(documented, encoded);
    let parsed: ClientMsg = serde_json::from_slice(&encoded[4..]).unwrap();
    assert!(matches!(parsed, ClientMsg::Ping(p) if p.nonce == 0));
}

#[test]
fn documented_error_codes_are_the_real_ones() {
    use naosoccer_proto::msg::ErrorCode::*;
    for code in [
        InvalidArgument,
        FailedPrecondition,
        NotFound,
        PermissionDenied,
        Unimplemented,
        ResourceExhausted,
        DeadlineExceeded,
        Unavailable,
        Internal,
    ] {
        let row = format!("| `{}` |", code.as_str());
        assert!(
            DOC.contains(&row),
            "error code {code} missing from the table"
        );
        assert_eq!(
            serde_json::to_value(code).unwrap(),
            Value::String(code.as_str().into())
        );
    }
}

#[test]
fn the_document_is_this_builds_version_with_a_changelog_row() {
    use naosoccer_proto::msg::PROTOCOL_VERSION;
    let title = DOC.lines().next().unwrap();
    assert!(
        title.ends_with(&format!("version {PROTOCOL_VERSION}")),
        "{title}"
    );
    let row = format!("| {PROTOCOL_VERSION} |");
    assert!(
        DOC.lines().any(|l| l.starts_with(&row)),
        "no changelog row for {PROTOCOL_VERSION}"
    );
}

/// Issue 39: the `hello` and `welcome` examples (and the Python client's
/// `hello`) name this build's version, so a client copied from them says
/// what the server says.
#[test]
fn examples_name_this_builds_version() {
    use naosoccer_proto::msg::PROTOCOL_VERSION;
    let mut seen = 0;
    for text in blocks("json") {
        let value: Value = serde_json::from_str(&text).unwrap();
        if matches!(value["type"].as_str(), Some("hello" | "welcome")) {
            let version: naosoccer_proto::msg::Version =
                serde_json::from_value(value["version"].clone()).unwrap();
            assert_eq!(version, PROTOCOL_VERSION, "{text}");
            seen += 1;
        }
    }
    assert_eq!(seen, 2, "one hello and one welcome example");
    let python = blocks("python").concat();
    let hello = format!(
        r#""version": {{"major": {}, "minor": {}}}"#,
        PROTOCOL_VERSION.major, PROTOCOL_VERSION.minor
    );
    assert!(
        python.contains(&hello),
        "the Python client's hello: {hello}"
    );
}

/// Issue 39: a goal kick's spot is the front corner of the goal area,
/// ±(field_length/2 − goal_area_depth), ±goal_area_width/2, as the
/// document says, (±2.4, ±1.7) by default.
#[test]
fn goal_kick_spot_is_the_front_corner_of_the_goal_area() {
    use naosoccer_proto::{SetPlayKind, Team};
    use naosoccer_referee::rules::{OutOfBoundsRule, Restart};
    use naosoccer_referee::{Field, MatchConfig};
    let cfg = MatchConfig::default();
    let r = &cfg.rules;
    assert_eq!((r.goal_area_depth, r.goal_area_width), (0.6, 3.4));
    assert_eq!((cfg.sim.field_length, cfg.sim.field_width), (6.0, 4.5));
    assert!(DOC.contains("that is (±2.4, ±1.7)"));
    let rule = OutOfBoundsRule::new(
        Field::from_sim(&cfg.sim),
        r.ball_inset,
        r.robot_out_margin,
        r.goal_area_depth,
        r.goal_area_width,
    );
    let at = |x: f32, y: f32, last: Option<Team>| {
        let Some(Restart { kind, team, x, y }) = rule.restart(x, y, last) else {
            panic!("({x}, {y}) is out");
        };
        assert_eq!(kind, SetPlayKind::GoalKick);
        (team, (x * 1e3).round() / 1e3, (y * 1e3).round() / 1e3)
    };
    // Blue last touched it, over red's goal line (+x), right of the goal.
    assert_eq!(at(3.2, -1.6, Some(Team::Blue)), (Team::Red, 2.4, -1.7));
    // Nobody touched it, over blue's line, left of the goal.
    assert_eq!(at(-3.3, 0.9, None), (Team::Blue, -2.4, 1.7));
    // Over the crossbar at y = 0: the + side.
    assert_eq!(at(3.2, 0.0, Some(Team::Blue)), (Team::Red, 2.4, 1.7));
}

/// Issue 39: the halves split the ticks as section 5 says, and a goal on
/// the first half's last tick counts but leaves the kick-off to the team
/// that did not kick off the first half, not to the team that conceded.
#[test]
fn a_goal_on_the_last_tick_of_the_first_half_leaves_the_kick_off_to_the_second_half() {
    use naosoccer_proto::{Action, Event, Team, Tick, ROBOTS};
    use naosoccer_referee::rules::Clock;
    use naosoccer_referee::{FirstKickOff, Match, MatchConfig};
    // 61 ticks: the first half is ticks 0..=29, the second 30..=60.
    let clock = Clock::new(6.1 / 60.0, 10.0, 2);
    assert_eq!(clock.total_ticks(), 61);
    assert_eq!([29, 30, 60].map(|t| clock.half(Tick::new(t))), [1, 2, 2]);

    let mut cfg = MatchConfig {
        minutes: 6.0 / 60.0,
        ..MatchConfig::default()
    };
    cfg.rules.first_kickoff = FirstKickOff::Blue;
    let mut m = Match::new(&cfg, 1).unwrap();
    assert_eq!(m.total_ticks(), 60);
    let stay = [Action::Stay; ROBOTS];
    while m.tick() < Tick::new(29) {
        m.step(&stay);
    }
    // Red scores into blue's goal (-x) on tick 29, the first half's last:
    // blue conceded, yet red kicks off the second half (blue kicked off the
    // first).
    m.sim_mut().place_ball(-2.95, 0.5);
    m.sim_mut().set_ball_velocity(-3.0, 0.0);
    let events: Vec<Event> = m.step(&stay).to_vec();
    let tick = Tick::new(29);
    let kinds: Vec<&Event> = events
        .iter()
        .filter(|e| {
            matches!(
                e,
                Event::Goal { .. } | Event::HalfTime { .. } | Event::KickOff { .. }
            )
        })
        .collect();
    assert!(
        matches!(
            kinds.as_slice(),
            [
                Event::Goal { tick: t0, team: Team::Red, .. },
                Event::HalfTime { tick: t1 },
                Event::KickOff { tick: t2, team: Team::Red },
            ] if [*t0, *t1, *t2] == [tick; 3]
        ),
        "{events:?}"
    );
    assert_eq!((m.score().blue, m.score().red), (0, 1));
    assert_eq!(m.half(), 2);
    assert_eq!(m.set_play().map(|(_, team, _)| team), Some(Team::Red));
}
