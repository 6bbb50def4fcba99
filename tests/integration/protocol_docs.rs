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
