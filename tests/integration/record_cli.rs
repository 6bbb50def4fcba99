//! `naosoccer match --record`, `replay` and `render` as a user runs them:
//! the real binary, real files.

use crate::common;

use common::{naosoccer, scratch, text};

#[test]
fn record_replay_summary_render_and_a_cut_file() {
    let file = scratch("record-cli", "m.mcap");
    let f = file.to_str().unwrap();
    let out = naosoccer(&[
        "match",
        "--seed",
        "9",
        "--minutes",
        "1",
        "--record",
        f,
        "--json",
    ]);
    assert!(out.status.success(), "{}", text(&out));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["recording"]["messages"]["/match/actions"], 600);
    assert_eq!(
        v["recording"]["bytes"],
        std::fs::metadata(&file).unwrap().len()
    );

    let out = naosoccer(&["replay", f]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out));
    assert_eq!(
        String::from_utf8_lossy(&out.stdout).trim(),
        "identical (600 ticks)"
    );

    let out = naosoccer(&["replay", f, "--summary"]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out));
    let s = String::from_utf8_lossy(&out.stdout);
    let score = format!(
        "final score: blue {} - {} red",
        v["score"]["blue"], v["score"]["red"]
    );
    assert!(s.contains(&score), "{s}");

    let png = scratch("record-cli", "m.png");
    let out = naosoccer(&["render", f, "--out", png.to_str().unwrap()]);
    assert!(out.status.success(), "{}", text(&out));
    let bytes = std::fs::read(&png).unwrap();
    assert_eq!(&bytes[1..4], b"PNG");

    // A server killed mid-match leaves a prefix of the file.
    let all = std::fs::read(&file).unwrap();
    let cut = scratch("record-cli", "cut.mcap");
    std::fs::write(&cut, &all[..all.len() / 2]).unwrap();
    let out = naosoccer(&["replay", cut.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2), "{}", text(&out));
    let s = String::from_utf8_lossy(&out.stdout);
    assert!(
        s.starts_with("identical (") && s.contains("cut short"),
        "{s}"
    );

    let junk = scratch("record-cli", "junk.mcap");
    std::fs::write(&junk, b"definitely not mcap").unwrap();
    let out = naosoccer(&["replay", junk.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(3), "{}", text(&out));
    assert!(
        text(&out).contains("not a naosoccer recording"),
        "{}",
        text(&out)
    );

    let _ = std::fs::remove_dir_all(file.parent().unwrap());
}
