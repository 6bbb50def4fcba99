//! `naosoccer render FILE --gif OUT.gif` as a user runs it: a real match
//! recorded to MCAP, drawn as a GIF, decoded back frame by frame.

use crate::common;

use common::{naosoccer, scratch, text};

use std::path::Path;

/// The GIF's size and every frame as the viewer shows it (palette indices,
/// each frame drawn over the ones before).
fn decode(path: &Path) -> (u16, u16, Vec<Vec<u8>>) {
    let mut opts = gif::DecodeOptions::new();
    opts.set_color_output(gif::ColorOutput::Indexed);
    let mut d = opts
        .read_info(std::fs::File::open(path).unwrap())
        .expect("a GIF");
    let (w, h) = (d.width(), d.height());
    let mut screen = vec![0u8; w as usize * h as usize];
    let mut frames = Vec::new();
    while let Some(f) = d.read_next_frame().expect("a frame") {
        for y in 0..f.height as usize {
            for x in 0..f.width as usize {
                let c = f.buffer[y * f.width as usize + x];
                if Some(c) != f.transparent {
                    let (sx, sy) = (f.left as usize + x, f.top as usize + y);
                    screen[sy * w as usize + sx] = c;
                }
            }
        }
        frames.push(screen.clone());
    }
    (w, h, frames)
}

#[test]
fn a_recorded_match_as_an_animated_gif() {
    let file = scratch("render-gif", "m.mcap");
    let f = file.to_str().unwrap();
    let out = naosoccer(&["match", "--seed", "3", "--minutes", "0.5", "--record", f]);
    assert!(out.status.success(), "{}", text(&out));

    // 300 ticks at 10 Hz; 5 game s per GIF s at 4 fps: every 12.5 -> 13 ticks,
    // ticks 0, 13, ..., 299: 24 frames.
    let gif_path = scratch("render-gif", "m.gif");
    let g = gif_path.to_str().unwrap();
    let args = [
        "render", f, "--gif", g, "--speed", "5", "--fps", "4", "--width", "320",
    ];
    let out = naosoccer(&args);
    assert!(out.status.success(), "{}", text(&out));
    let (w, h, frames) = decode(&gif_path);
    assert_eq!(w, 320);
    assert!(
        (160..300).contains(&h),
        "height {h} follows the pitch (9 x 6 m plus margins) and the banner"
    );
    assert!(
        String::from_utf8_lossy(&out.stdout)
            .contains(&format!("24 frames of {w}x{h}, every 13 ticks")),
        "{}",
        text(&out)
    );
    assert_eq!(frames.len(), 24);
    assert_ne!(frames[0], frames[23], "the robots and the clock move");
    assert_ne!(frames[0], frames[1]);

    // The same recording and options give the same bytes.
    let again = scratch("render-gif", "again.gif");
    let mut args2 = args;
    args2[3] = again.to_str().unwrap();
    assert!(naosoccer(&args2).status.success());
    assert_eq!(
        std::fs::read(&gif_path).unwrap(),
        std::fs::read(&again).unwrap()
    );

    // A part of the match, and the PNG still alongside: 10 s to 20 s at the
    // defaults (10 game s per s, 10 fps: every 10th tick) is 11 frames.
    let part = scratch("render-gif", "part.gif");
    let png = scratch("render-gif", "m.png");
    let out = naosoccer(&[
        "render",
        f,
        "--gif",
        part.to_str().unwrap(),
        "--from",
        "10",
        "--to",
        "20",
        "--out",
        png.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", text(&out));
    let (w, _, frames) = decode(&part);
    assert_eq!((w, frames.len()), (480, 11));
    assert_eq!(&std::fs::read(&png).unwrap()[1..4], b"PNG");

    // Neither output asked for is an error, and so is an impossible rate.
    let out = naosoccer(&["render", f]);
    assert!(!out.status.success());
    let out = naosoccer(&["render", f, "--gif", g, "--fps", "0"]);
    assert!(!out.status.success());
    assert!(text(&out).contains("--fps"), "{}", text(&out));
}

#[test]
fn help_explains_the_gif() {
    let out = naosoccer(&["render", "--help"]);
    let s = String::from_utf8_lossy(&out.stdout);
    for needle in [
        "--gif", "--speed", "--fps", "--from", "--to", "score", "clock",
    ] {
        assert!(s.contains(needle), "{needle} missing from:\n{s}");
    }
}
