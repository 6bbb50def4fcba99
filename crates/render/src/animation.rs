//! `naosoccer render FILE --gif OUT.gif`: a recording as an animated top
//! view, with the score and the clock; and one frame of it, drawn from one
//! state ([`draw_frame`], the Python env's `render()`).
//!
//! Frames are drawn straight in a fixed palette (no colour quantisation, so
//! the same recording and options give the same bytes), and every frame after
//! the first holds only the rectangle that changed, the unchanged pixels of
//! it transparent: a match is mostly still grass, which keeps clips small.

use std::fs::File;
use std::io::BufWriter;
use std::path::Path;

use anyhow::{bail, Context};
use naosoccer_proto::{Tick, ROBOTS};
use naosoccer_record::{Recording, StateRecord};
use naosoccer_sim::SimConfig;

/// What `render --gif` was asked for.
#[derive(Debug, Clone, Copy)]
pub struct GifOptions {
    /// Image width in pixels (the height follows the pitch, plus the banner).
    pub width: u32,
    /// Game seconds per second of GIF.
    pub speed: f64,
    /// GIF frames per second.
    pub fps: u32,
    /// The part of the match drawn, in game seconds.
    pub from: f64,
    pub to: Option<f64>,
}

/// What was written.
#[derive(Debug, Clone, Copy)]
pub struct GifSummary {
    pub frames: usize,
    /// Ticks between two frames.
    pub step: u64,
    pub width: u16,
    pub height: u16,
    pub first_tick: Tick,
    pub last_tick: Tick,
}

// The palette. Index 0 is never drawn: it marks unchanged pixels.
const KEY: u8 = 0;
const GRASS: u8 = 1;
const WHITE: u8 = 2;
const GOAL: u8 = 3;
const BANNER: u8 = 4;
const BLUE: u8 = 5; // 5..=8, one shade per player
const RED: u8 = 9; // 9..=12
const BALL: u8 = 13;
const YELLOW: u8 = 14;
const BLACK: u8 = 15;
const FALLEN: u8 = 16;
const PALETTE: [[u8; 3]; 32] = {
    let mut p = [[0u8; 3]; 32];
    p[KEY as usize] = [255, 0, 255];
    p[GRASS as usize] = [28, 110, 40];
    p[WHITE as usize] = [255, 255, 255];
    p[GOAL as usize] = [210, 210, 210];
    p[BANNER as usize] = [24, 24, 24];
    p[BLUE as usize] = [40, 90, 255];
    p[BLUE as usize + 1] = [80, 130, 255];
    p[BLUE as usize + 2] = [120, 170, 255];
    p[BLUE as usize + 3] = [160, 210, 255];
    p[RED as usize] = [255, 50, 40];
    p[RED as usize + 1] = [255, 90, 80];
    p[RED as usize + 2] = [255, 130, 120];
    p[RED as usize + 3] = [255, 170, 160];
    p[BALL as usize] = [255, 150, 0];
    p[YELLOW as usize] = [255, 225, 0];
    p[BLACK as usize] = [0, 0, 0];
    p[FALLEN as usize] = [110, 110, 110];
    p
};

/// An indexed-colour picture.
#[derive(Clone)]
struct Canvas {
    w: i32,
    h: i32,
    px: Vec<u8>,
}

impl Canvas {
    fn new(w: i32, h: i32, fill: u8) -> Canvas {
        Canvas {
            w,
            h,
            px: vec![fill; (w * h) as usize],
        }
    }

    fn rect(&mut self, x0: i32, y0: i32, x1: i32, y1: i32, c: u8) {
        for y in y0.max(0)..y1.min(self.h) {
            for x in x0.max(0)..x1.min(self.w) {
                self.px[(y * self.w + x) as usize] = c;
            }
        }
    }

    fn disc(&mut self, cx: f64, cy: f64, r: f64, c: u8) {
        let (x0, x1) = ((cx - r).floor() as i32, (cx + r).ceil() as i32);
        let (y0, y1) = ((cy - r).floor() as i32, (cy + r).ceil() as i32);
        for y in y0.max(0)..=y1.min(self.h - 1) {
            for x in x0.max(0)..=x1.min(self.w - 1) {
                let (dx, dy) = (x as f64 + 0.5 - cx, y as f64 + 0.5 - cy);
                if dx * dx + dy * dy <= r * r {
                    self.px[(y * self.w + x) as usize] = c;
                }
            }
        }
    }

    /// A line `t` pixels thick.
    fn line(&mut self, a: (f64, f64), b: (f64, f64), t: i32, c: u8) {
        let n = (b.0 - a.0).abs().max((b.1 - a.1).abs()).ceil().max(1.0) as i32;
        for i in 0..=n {
            let f = i as f64 / n as f64;
            let x = (a.0 + f * (b.0 - a.0)).round() as i32 - t / 2;
            let y = (a.1 + f * (b.1 - a.1)).round() as i32 - t / 2;
            self.rect(x, y, x + t, y + t, c);
        }
    }

    /// Text in a 3×5 pixel font, each font pixel `s`×`s`; returns the width.
    fn text(&mut self, x: i32, y: i32, s: i32, text: &str, c: u8) -> i32 {
        let mut cx = x;
        for ch in text.chars() {
            let bits = glyph(ch);
            for row in 0..5 {
                for col in 0..3 {
                    if bits & (1 << (14 - (row * 3 + col))) != 0 {
                        self.rect(
                            cx + col * s,
                            y + row * s,
                            cx + (col + 1) * s,
                            y + (row + 1) * s,
                            c,
                        );
                    }
                }
            }
            cx += 4 * s;
        }
        cx - x - s
    }
}

fn text_width(text: &str, s: i32) -> i32 {
    text.chars().count() as i32 * 4 * s - s
}

/// 3×5 glyphs, row by row from the top, most significant bit first.
fn glyph(ch: char) -> u16 {
    match ch {
        '0' => 0b111_101_101_101_111,
        '1' => 0b010_110_010_010_111,
        '2' => 0b111_001_111_100_111,
        '3' => 0b111_001_111_001_111,
        '4' => 0b101_101_111_001_001,
        '5' => 0b111_100_111_001_111,
        '6' => 0b111_100_111_101_111,
        '7' => 0b111_001_010_010_010,
        '8' => 0b111_101_111_101_111,
        '9' => 0b111_101_111_001_111,
        ':' => 0b000_010_000_010_000,
        '-' => 0b000_000_111_000_000,
        _ => 0,
    }
}

/// Pixel geometry of the top view.
struct View {
    x0: f64,
    y1: f64,
    ppm: f64,
    banner: i32,
    font: i32,
}

impl View {
    fn px(&self, x: f32, y: f32) -> (f64, f64) {
        (
            (x as f64 - self.x0) * self.ppm,
            self.banner as f64 + (self.y1 - y as f64) * self.ppm,
        )
    }
}

fn background(sim: &SimConfig, width: u32) -> (View, Canvas) {
    let (hl, hw) = (sim.field_length as f64 / 2.0, sim.field_width as f64 / 2.0);
    let margin = sim.ground_margin.max(sim.goal_depth) as f64;
    let (x0, x1) = (-hl - margin, hl + margin);
    let (y0, y1) = (-hw - margin, hw + margin);
    let ppm = width as f64 / (x1 - x0);
    let font = (width as i32 / 160).max(2);
    let banner = 7 * font;
    let height = banner + ((y1 - y0) * ppm).round() as i32;
    let view = View {
        x0,
        y1,
        ppm,
        banner,
        font,
    };
    let mut c = Canvas::new(width as i32, height, GRASS);
    c.rect(0, 0, width as i32, banner, BANNER);
    let t = ((0.05 * ppm).round() as i32).max(1);
    let p = |x: f64, y: f64| view.px(x as f32, y as f32);
    let corners = [(-hl, -hw), (hl, -hw), (hl, hw), (-hl, hw), (-hl, -hw)];
    for w in corners.windows(2) {
        c.line(p(w[0].0, w[0].1), p(w[1].0, w[1].1), t, WHITE);
    }
    c.line(p(0.0, -hw), p(0.0, hw), t, WHITE);
    for i in 0..96 {
        let a = |i: i32| i as f64 / 96.0 * std::f64::consts::TAU;
        let r = 0.75;
        c.line(
            p(r * a(i).cos(), r * a(i).sin()),
            p(r * a(i + 1).cos(), r * a(i + 1).sin()),
            t,
            WHITE,
        );
    }
    let (gw, depth) = (sim.goal_width as f64 / 2.0, sim.goal_depth as f64);
    for side in [-1.0, 1.0] {
        let post = [
            (side * hl, -gw),
            (side * (hl + depth), -gw),
            (side * (hl + depth), gw),
            (side * hl, gw),
        ];
        for w in post.windows(2) {
            c.line(p(w[0].0, w[0].1), p(w[1].0, w[1].1), t + 1, GOAL);
        }
    }
    (view, c)
}

fn draw_state(c: &mut Canvas, view: &View, s: &StateRecord) {
    let r = (0.2 * view.ppm).max(3.0);
    for (i, robot) in s.robots.iter().enumerate() {
        let (team_base, player) = if i < ROBOTS / 2 {
            (BLUE, i)
        } else {
            (RED, i - ROBOTS / 2)
        };
        let colour = team_base + player as u8;
        let (x, y) = view.px(robot.x, robot.y);
        if s.possession.map(|p| p.index()) == Some(i) {
            c.disc(x, y, r + 2.0, YELLOW);
        }
        c.disc(x, y, r, colour);
        if robot.fallen {
            c.disc(x, y, r * 0.55, FALLEN);
        }
        let (dx, dy) = (robot.heading.cos() as f64, -robot.heading.sin() as f64);
        let t = ((r / 4.0).round() as i32).max(1);
        c.line((x, y), (x + dx * r * 1.6, y + dy * r * 1.6), t, BLACK);
    }
    let (bx, by) = view.px(s.ball.x, s.ball.y);
    c.disc(bx, by, (0.12 * view.ppm).max(2.5), BALL);

    // The banner: blue square, score, red square; the clock at the right.
    let f = view.font;
    let score = format!("{} - {}", s.score.blue, s.score.red);
    let sw = text_width(&score, f);
    let mut x = f * 2;
    c.rect(x, f, x + 5 * f, 6 * f, BLUE);
    x += 7 * f;
    c.text(x, f, f, &score, WHITE);
    x += sw + 2 * f;
    c.rect(x, f, x + 5 * f, 6 * f, RED);
    let secs = s.time.max(0.0) as u64;
    let clock = format!("{:02}:{:02}", secs / 60, secs % 60);
    let cw = text_width(&clock, f);
    c.text(c.w - 2 * f - cw, f, f, &clock, WHITE);
}

/// The narrowest and widest pictures drawn, in pixels.
pub const MIN_WIDTH: u32 = 120;
pub const MAX_WIDTH: u32 = 4000;

/// One picture of the top view: 8-bit RGB, `width` × `height` pixels, rows
/// top to bottom, three bytes a pixel.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct RgbFrame {
    pub width: u32,
    pub height: u32,
    pub pixels: Vec<u8>,
}

/// Draws `state` as `render --gif` draws each of its frames: the pitch of
/// `sim`, the robots (the ball's controller ringed), the ball, the score and
/// the clock. `width` is clamped to [`MIN_WIDTH`]..=[`MAX_WIDTH`]; the
/// height follows the pitch, plus the banner.
pub fn draw_frame(sim: &SimConfig, state: &StateRecord, width: u32) -> RgbFrame {
    let (view, mut c) = background(sim, width.clamp(MIN_WIDTH, MAX_WIDTH));
    draw_state(&mut c, &view, state);
    RgbFrame {
        width: c.w as u32,
        height: c.h as u32,
        pixels: c.px.iter().flat_map(|&i| PALETTE[i as usize]).collect(),
    }
}

/// Writes `rec` as an animated GIF at `out`.
pub fn write_gif(rec: &Recording, out: &Path, opts: GifOptions) -> anyhow::Result<GifSummary> {
    if !(1..=50).contains(&opts.fps) {
        bail!("--fps must be between 1 and 50 (GIF frame delays are in hundredths of a second)");
    }
    if !(opts.speed > 0.0 && opts.speed.is_finite()) {
        bail!("--speed must be a positive number of game seconds per second");
    }
    let states = &rec.states;
    let Some(last) = states.last() else {
        bail!("the recording has no states to draw");
    };
    let hz = rec.meta.control_hz as f64;
    let step = ((opts.speed * hz / opts.fps as f64).round() as u64).max(1);
    let first_tick = Tick::new((opts.from.max(0.0) * hz).round() as u64);
    let last_tick = opts
        .to
        .map(|t| Tick::new((t * hz).round() as u64).min(last.tick))
        .unwrap_or(last.tick);
    if first_tick > last_tick {
        bail!(
            "--from {} s is after the end of the part drawn ({} s)",
            opts.from,
            last_tick.get() as f64 / hz
        );
    }
    let width = opts.width.clamp(MIN_WIDTH, MAX_WIDTH);
    let (view, bg) = background(&rec.meta.config.sim, width);
    let (w, h) = (bg.w as u16, bg.h as u16);

    let palette: Vec<u8> = PALETTE.iter().flatten().copied().collect();
    let file = File::create(out).with_context(|| format!("creating {}", out.display()))?;
    let mut enc = gif::Encoder::new(BufWriter::new(file), w, h, &palette)?;
    enc.set_repeat(gif::Repeat::Infinite)?;
    let delay = (100.0 / opts.fps as f64).round() as u16;

    let mut prev: Option<Canvas> = None;
    let mut frames = 0;
    let mut drawn_last = first_tick;
    for s in states
        .iter()
        .filter(|s| s.tick >= first_tick && s.tick <= last_tick)
        .filter(|s| (s.tick - first_tick).is_multiple_of(step))
    {
        let mut c = bg.clone();
        draw_state(&mut c, &view, s);
        let frame = match &prev {
            None => gif::Frame {
                width: w,
                height: h,
                delay,
                buffer: c.px.clone().into(),
                ..gif::Frame::default()
            },
            Some(p) => delta_frame(p, &c, delay),
        };
        enc.write_frame(&frame)?;
        prev = Some(c);
        frames += 1;
        drawn_last = s.tick;
    }
    enc.into_inner()?
        .into_inner()
        .map_err(|e| e.into_error())?
        .sync_all()?;
    Ok(GifSummary {
        frames,
        step,
        width: w,
        height: h,
        first_tick,
        last_tick: drawn_last,
    })
}

/// The rectangle of `next` that differs from `prev`, unchanged pixels in it
/// transparent (drawn over `prev`, which stays).
fn delta_frame(prev: &Canvas, next: &Canvas, delay: u16) -> gif::Frame<'static> {
    let (mut x0, mut y0, mut x1, mut y1) = (next.w, next.h, -1, -1);
    for y in 0..next.h {
        for x in 0..next.w {
            let i = (y * next.w + x) as usize;
            if prev.px[i] != next.px[i] {
                x0 = x0.min(x);
                x1 = x1.max(x);
                y0 = y0.min(y);
                y1 = y1.max(y);
            }
        }
    }
    if x1 < 0 {
        // Nothing moved: one transparent pixel keeps the frame's time.
        return gif::Frame {
            width: 1,
            height: 1,
            delay,
            transparent: Some(KEY),
            dispose: gif::DisposalMethod::Keep,
            buffer: vec![KEY].into(),
            ..gif::Frame::default()
        };
    }
    let mut buf = Vec::with_capacity(((x1 - x0 + 1) * (y1 - y0 + 1)) as usize);
    for y in y0..=y1 {
        for x in x0..=x1 {
            let i = (y * next.w + x) as usize;
            buf.push(if prev.px[i] == next.px[i] {
                KEY
            } else {
                next.px[i]
            });
        }
    }
    gif::Frame {
        left: x0 as u16,
        top: y0 as u16,
        width: (x1 - x0 + 1) as u16,
        height: (y1 - y0 + 1) as u16,
        delay,
        transparent: Some(KEY),
        dispose: gif::DisposalMethod::Keep,
        buffer: buf.into(),
        ..gif::Frame::default()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use naosoccer_referee::{Match, MatchConfig};

    /// The mean pixel column and row of `colour` in `f`, and how many.
    fn centroid(f: &RgbFrame, colour: [u8; 3]) -> (f64, f64, usize) {
        let (mut x, mut y, mut n) = (0.0, 0.0, 0);
        for (i, px) in f.pixels.chunks_exact(3).enumerate() {
            if px == colour {
                x += (i % f.width as usize) as f64;
                y += (i / f.width as usize) as f64;
                n += 1;
            }
        }
        (x / n.max(1) as f64, y / n.max(1) as f64, n)
    }

    #[test]
    fn a_frame_is_the_gif_drawing_of_one_state() {
        let cfg = MatchConfig::default();
        let m = Match::new(&cfg, 3).unwrap();
        let mut state = StateRecord::of(&m);
        let a = draw_frame(&cfg.sim, &state, 640);
        assert_eq!(a.width, 640);
        assert_eq!(a.pixels.len(), (a.width * a.height * 3) as usize);
        // Every pixel is a colour of the palette, and every robot is drawn.
        assert!(a
            .pixels
            .chunks_exact(3)
            .all(|px| PALETTE.iter().any(|p| p == px)));
        for colour in [BLUE, BLUE + 3, RED, RED + 3] {
            assert!(centroid(&a, PALETTE[colour as usize]).2 > 0, "{colour}");
        }
        // The ball one metre further +x (blue's attack) is drawn ppm pixels
        // to the right; one metre further +y, ppm pixels higher up.
        let sim = &cfg.sim;
        let margin = sim.ground_margin.max(sim.goal_depth);
        let ppm = 640.0 / f64::from(sim.field_length + 2.0 * margin);
        let ball = PALETTE[BALL as usize];
        let (ax, ay, an) = centroid(&a, ball);
        state.ball.x += 1.0;
        let b = draw_frame(&cfg.sim, &state, 640);
        assert_eq!((a.width, a.height), (b.width, b.height));
        let (bx, by, bn) = centroid(&b, ball);
        state.ball.y += 1.0;
        let (cx, cy, _) = centroid(&draw_frame(&cfg.sim, &state, 640), ball);
        assert!(an > 0 && bn > 0);
        assert!(
            (bx - ax - ppm).abs() < 1.0 && (by - ay).abs() < 1.0,
            "{ax} -> {bx}"
        );
        assert!(
            (ay - cy - ppm).abs() < 1.0 && (cx - bx).abs() < 1.0,
            "{ay} -> {cy}"
        );
        // Widths out of range are clamped.
        assert_eq!(draw_frame(&cfg.sim, &state, 10).width, MIN_WIDTH);
    }
}
