//! The top level of a JSON object, read without building it: one pass, an
//! explicit stack, no recursion. serde_json refuses a payload nested more
//! than 128 levels deep (its parser recurses), yet the error answering such
//! a frame must still name its `type` (docs/PROTOCOL.md, `error`; issue 39).
//! Strings and numbers are checked by serde_json itself, one token at a
//! time, so this accepts exactly the JSON serde_json accepts, depth aside.
//! Work and memory are linear in the payload, which the frame cap bounds.

/// The value of a member of the top-level object.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Member<'a> {
    /// A string, number, `true`, `false` or `null`: its JSON text.
    Scalar(&'a [u8]),
    /// An object or an array.
    Container,
}

/// The members of a top-level object that a frame's head is read from. As
/// in a `serde_json::Map`, the last of duplicate keys wins.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub(crate) struct TopLevel<'a> {
    pub ty: Option<Member<'a>>,
    pub tick: Option<Member<'a>>,
}

#[derive(Clone, Copy, PartialEq, Eq)]
enum Want {
    Value,
    /// Just after `[`.
    ValueOrClose,
    /// Just after `{`.
    KeyOrClose,
    /// After a `,` in an object.
    Key,
    /// A value is complete: a `,`, a closing bracket or the end.
    AfterValue,
}

#[derive(Clone, Copy)]
enum Key {
    Type,
    Tick,
    Other,
}

/// The `type` and `tick` members of `payload` when it is one JSON object
/// (surrounding whitespace allowed); `None` when it is not valid JSON or
/// not an object.
pub(crate) fn top_level(payload: &[u8]) -> Option<TopLevel<'_>> {
    let b = payload;
    let mut i = skip_ws(b, 0);
    if b.get(i) != Some(&b'{') {
        return None;
    }
    let mut out = TopLevel::default();
    // The open containers, innermost last: `{` or `[`.
    let mut stack: Vec<u8> = Vec::new();
    let mut key = Key::Other;
    let mut want = Want::Value;
    loop {
        i = skip_ws(b, i);
        match want {
            Want::Value | Want::ValueOrClose => {
                let c = *b.get(i)?;
                if c == b']' && want == Want::ValueOrClose {
                    stack.pop();
                    i += 1;
                    want = Want::AfterValue;
                    continue;
                }
                let member = stack.len() == 1;
                let value = match c {
                    b'{' | b'[' => {
                        stack.push(c);
                        i += 1;
                        want = if c == b'{' {
                            Want::KeyOrClose
                        } else {
                            Want::ValueOrClose
                        };
                        Member::Container
                    }
                    b'"' => {
                        let end = string_end(b, i)?;
                        let text = &b[i..end];
                        serde_json::from_slice::<String>(text).ok()?;
                        i = end;
                        want = Want::AfterValue;
                        Member::Scalar(text)
                    }
                    _ => {
                        let end = i + b[i..]
                            .iter()
                            .take_while(|c| c.is_ascii_alphanumeric() || b"+-.".contains(c))
                            .count();
                        let text = &b[i..end];
                        if text.is_empty() {
                            return None;
                        }
                        serde_json::from_slice::<serde_json::Value>(text).ok()?;
                        i = end;
                        want = Want::AfterValue;
                        Member::Scalar(text)
                    }
                };
                if member {
                    match key {
                        Key::Type => out.ty = Some(value),
                        Key::Tick => out.tick = Some(value),
                        Key::Other => {}
                    }
                }
            }
            Want::KeyOrClose | Want::Key => {
                let c = *b.get(i)?;
                if c == b'}' && want == Want::KeyOrClose {
                    stack.pop();
                    i += 1;
                    want = Want::AfterValue;
                    continue;
                }
                if c != b'"' {
                    return None;
                }
                let end = string_end(b, i)?;
                let name = serde_json::from_slice::<String>(&b[i..end]).ok()?;
                if stack.len() == 1 {
                    key = match name.as_str() {
                        "type" => Key::Type,
                        "tick" => Key::Tick,
                        _ => Key::Other,
                    };
                }
                i = skip_ws(b, end);
                if b.get(i) != Some(&b':') {
                    return None;
                }
                i += 1;
                want = Want::Value;
            }
            Want::AfterValue => {
                let Some(&open) = stack.last() else {
                    // The top-level object is complete: only whitespace may follow.
                    return (i == b.len()).then_some(out);
                };
                match (*b.get(i)?, open) {
                    (b',', b'{') => want = Want::Key,
                    (b',', _) => want = Want::Value,
                    (b'}', b'{') | (b']', b'[') => {
                        stack.pop();
                    }
                    _ => return None,
                }
                i += 1;
            }
        }
    }
}

/// JSON's whitespace, as serde_json reads it.
fn skip_ws(b: &[u8], mut i: usize) -> usize {
    while matches!(b.get(i), Some(b' ' | b'\n' | b'\t' | b'\r')) {
        i += 1;
    }
    i
}

/// Just past the closing quote of the string starting at `b[start]` (a `"`).
fn string_end(b: &[u8], start: usize) -> Option<usize> {
    let mut i = start + 1;
    loop {
        match *b.get(i)? {
            b'"' => return Some(i + 1),
            b'\\' => i += 2,
            _ => i += 1,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// What `top_level` reports, read the way serde_json would read the
    /// whole payload (it builds the tree; the oracle for shallow input).
    fn oracle(payload: &[u8]) -> Option<(Option<serde_json::Value>, Option<serde_json::Value>)> {
        let Ok(serde_json::Value::Object(map)) = serde_json::from_slice(payload) else {
            return None;
        };
        Some((map.get("type").cloned(), map.get("tick").cloned()))
    }

    fn read(m: Option<Member<'_>>) -> Option<serde_json::Value> {
        match m? {
            Member::Scalar(text) => Some(serde_json::from_slice(text).unwrap()),
            // The oracle's containers, compared by kind only.
            Member::Container => Some(serde_json::Value::Array(vec![])),
        }
    }

    fn container_kind(v: Option<serde_json::Value>) -> Option<serde_json::Value> {
        v.map(|v| match v {
            serde_json::Value::Array(_) | serde_json::Value::Object(_) => {
                serde_json::Value::Array(vec![])
            }
            other => other,
        })
    }

    fn agrees(payload: &[u8]) {
        let ours = top_level(payload).map(|t| (read(t.ty), read(t.tick)));
        let theirs = oracle(payload).map(|(t, k)| (container_kind(t), container_kind(k)));
        assert_eq!(ours, theirs, "{:?}", String::from_utf8_lossy(payload));
    }

    /// Every sequence of up to four of these tokens, after each of these
    /// prefixes, reads as serde_json reads it: valid or not, and the same
    /// `type` and `tick`.
    #[test]
    fn agrees_with_serde_json_on_every_short_token_sequence() {
        const TOKENS: [&str; 16] = [
            "{",
            "}",
            "[",
            "]",
            ",",
            ":",
            " ",
            r#""type""#,
            r#""tick""#,
            r#""ping""#,
            "7",
            "-0",
            "1.5e3",
            "1e400",
            "null",
            r#""\ud800""#,
        ];
        const PREFIXES: [&str; 4] = ["", "{", r#"{"type":"#, r#"{"type":"action","tick":"#];
        let mut seq = Vec::new();
        for prefix in PREFIXES {
            for n in 0..=4u32 {
                for mut code in 0..TOKENS.len().pow(n) {
                    seq.clear();
                    seq.extend_from_slice(prefix.as_bytes());
                    for _ in 0..n {
                        seq.extend_from_slice(TOKENS[code % TOKENS.len()].as_bytes());
                        code /= TOKENS.len();
                    }
                    agrees(&seq);
                }
            }
        }
    }

    #[test]
    fn agrees_with_serde_json_on_strings_numbers_and_whitespace() {
        for payload in [
            r#" {"type" : "ping" , "nonce":17 } "#,
            r#"{"typ\u0065":"ping"}"#,
            r#"{"type":"pi\"ng"}"#,
            r#"{"type":"ping","type":7}"#,
            r#"{"type":7,"type":"ping"}"#,
            r#"{"type":"action","tick":12345678901234567890}"#,
            r#"{"type":"action","tick":123456789012345678901}"#,
            r#"{"type":"action","tick":5.0}"#,
            r#"{"type":"action","tick":-3}"#,
            r#"{"type":"action","tick":01}"#,
            r#"{"type":"action","tick":1.}"#,
            r#"{"type":"action","tick":1E2}"#,
            r#"{"type":"action","tick":{"tick":3}}"#,
            r#"{"x":{"type":"ping"},"tick":[3]}"#,
            r#"{"type":"ping","x":tru}"#,
            r#"{"type":"ping","x":true,}"#,
            r#"{"type":"ping","x":[1,]}"#,
            r#"{"type":"ping"}x"#,
            r#"{"type":"ping"}{}"#,
            "{\"type\":\"ping\u{1}\"}",
            "{\"type\":\"p\u{e9}ng\"}",
            "\u{feff}{\"type\":\"ping\"}",
            "{\"type\":\"ping\"}\u{a0}",
            r#"{"type":"ping","x":"\x"}"#,
            r#"{"type":"ping","x":"\u12"}"#,
            r#"{"type":"ping","x":"\udc00\ud800"}"#,
            r#"{"type":"ping","x":"\ud83d\ude00"}"#,
            r#"{"type":"ping","x":NaN}"#,
            r#"{"type":"ping","x":-}"#,
            r#"{"type":"ping","x":+1}"#,
            r#"{"type":"ping""#,
            r#"{"type":"ping"#,
            "",
            " ",
        ] {
            agrees(payload.as_bytes());
        }
        agrees(b"{\"type\":\"p\xffng\"}");
        agrees(b"{\"type\":\"ping\",\"x\":\"\xc3\"}");
    }

    /// Issue 39: nesting past serde_json's limit still has a head.
    #[test]
    fn reads_the_head_of_a_payload_nested_thirty_thousand_deep() {
        let deep = |open: &str, close: &str| {
            format!(
                r#"{{"type":"create_match","x":{}0{},"tick":4}}"#,
                open.repeat(30_000),
                close.repeat(30_000)
            )
        };
        for (open, close) in [("[", "]"), (r#"{"a":"#, "}")] {
            let payload = deep(open, close);
            assert!(serde_json::from_str::<serde_json::Value>(&payload).is_err());
            let top = top_level(payload.as_bytes()).expect("valid JSON");
            assert_eq!(top.ty, Some(Member::Scalar(br#""create_match""#)));
            assert_eq!(top.tick, Some(Member::Scalar(b"4")));
            // One bracket short is not JSON.
            let cut = payload.replacen(close, "", 1);
            assert_eq!(top_level(cut.as_bytes()), None);
        }
    }
}
