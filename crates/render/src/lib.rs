//! The top view drawn from a recording's states, as one PNG and as an
//! animated GIF (`naosoccer render`), and one state drawn as one RGB frame
//! (the Python env's `render()`).
//!
//! Its own crate so that the drawing loops are compiled optimised while the
//! `naosoccer` binary's own code, which only parses arguments and
//! orchestrates, is not (a shorter fresh build, issue 14).

use std::path::Path;

use anyhow::Context;
use naosoccer_proto::{Event, Team, ROBOTS};
use naosoccer_record::Recording;

mod animation;

pub use animation::{
    draw_frame, write_gif, GifOptions, GifSummary, RgbFrame, MAX_WIDTH, MIN_WIDTH,
};

/// What `render_png` drew.
#[derive(Debug, Clone, Copy)]
pub struct PngSummary {
    /// Ticks the recording spans.
    pub ticks: usize,
    /// Goals marked.
    pub goals: usize,
}

/// Draws `rec` as one top view of the pitch into the PNG file `out`, `width`
/// pixels wide (at least 200; the height follows the pitch): the field, every
/// robot's path and last spot, the ball's path, and a ring where each goal
/// was scored.
pub fn render_png(rec: &Recording, out: &Path, width: u32) -> anyhow::Result<PngSummary> {
    use plotters::prelude::*;

    let sim = &rec.meta.config.sim;
    let (hl, hw) = (sim.field_length / 2.0, sim.field_width / 2.0);
    let margin = sim.ground_margin.max(sim.goal_depth) as f64;
    let (x0, x1) = (-(hl as f64) - margin, hl as f64 + margin);
    let (y0, y1) = (-(hw as f64) - margin, hw as f64 + margin);
    let width = width.max(200);
    let height = ((width as f64) * (y1 - y0) / (x1 - x0)).round() as u32;

    // Drawn into memory and written with the `png` crate: plotters' own file
    // output would pull in the whole `image` crate for this one PNG.
    let mut pixels = vec![0u8; width as usize * height as usize * 3];
    let root = BitMapBackend::with_buffer(&mut pixels, (width, height)).into_drawing_area();
    root.fill(&RGBColor(28, 110, 40))?;
    let mut chart = ChartBuilder::on(&root).build_cartesian_2d(x0..x1, y0..y1)?;
    let white = ShapeStyle::from(&WHITE).stroke_width(3);
    let (hl, hw) = (hl as f64, hw as f64);
    chart.draw_series(std::iter::once(PathElement::new(
        vec![(-hl, -hw), (hl, -hw), (hl, hw), (-hl, hw), (-hl, -hw)],
        white,
    )))?;
    chart.draw_series(std::iter::once(PathElement::new(
        vec![(0.0, -hw), (0.0, hw)],
        white,
    )))?;
    chart.draw_series(std::iter::once(PathElement::new(
        (0..=64)
            .map(|i| {
                let a = i as f64 / 64.0 * std::f64::consts::TAU;
                (0.75 * a.cos(), 0.75 * a.sin())
            })
            .collect::<Vec<_>>(),
        white,
    )))?;
    let gw = (sim.goal_width / 2.0) as f64;
    let depth = sim.goal_depth as f64;
    for side in [-1.0, 1.0] {
        chart.draw_series(std::iter::once(PathElement::new(
            vec![
                (side * hl, -gw),
                (side * (hl + depth), -gw),
                (side * (hl + depth), gw),
                (side * hl, gw),
            ],
            ShapeStyle::from(&RGBColor(230, 230, 230)).stroke_width(4),
        )))?;
    }

    let shades = |team: Team, player: usize| -> RGBColor {
        let k = 40 * player as u8;
        match team {
            Team::Blue => RGBColor(40 + k, 90 + k, 255),
            Team::Red => RGBColor(255, 50 + k, 40 + k),
        }
    };
    for r in 0..ROBOTS {
        let team = if r < ROBOTS / 2 {
            Team::Blue
        } else {
            Team::Red
        };
        let color = shades(team, r % (ROBOTS / 2));
        let path: Vec<(f64, f64)> = rec
            .states
            .iter()
            .map(|s| (s.robots[r].x as f64, s.robots[r].y as f64))
            .collect();
        chart.draw_series(split_at_jumps(&path).map(|seg| {
            PathElement::new(
                seg.to_vec(),
                ShapeStyle::from(&color.mix(0.55)).stroke_width(2),
            )
        }))?;
        if let Some(&(x, y)) = path.last() {
            chart.draw_series(std::iter::once(Circle::new((x, y), 9, color.filled())))?;
        }
    }
    let ball: Vec<(f64, f64)> = rec
        .states
        .iter()
        .map(|s| (s.ball.x as f64, s.ball.y as f64))
        .collect();
    chart.draw_series(split_at_jumps(&ball).map(|seg| {
        PathElement::new(
            seg.to_vec(),
            ShapeStyle::from(&RGBColor(255, 150, 0)).stroke_width(2),
        )
    }))?;
    // Goals: where the ball crossed, as a ring in the scoring team's colour.
    for e in &rec.events {
        if let Event::Goal { tick, team, .. } = e {
            let at = rec
                .states
                .iter()
                .rev()
                .find(|s| s.tick < *tick)
                .map(|s| (s.ball.x as f64, s.ball.y as f64));
            if let Some(p) = at {
                chart.draw_series(std::iter::once(Circle::new(
                    p,
                    16,
                    ShapeStyle::from(&shades(*team, 0)).stroke_width(5),
                )))?;
                chart.draw_series(std::iter::once(Circle::new(p, 6, YELLOW.filled())))?;
            }
        }
    }
    root.present()?;
    drop((chart, root));
    write_png(out, width, height, &pixels).with_context(|| format!("writing {}", out.display()))?;
    Ok(PngSummary {
        ticks: rec.states.len().saturating_sub(1),
        goals: rec
            .events
            .iter()
            .filter(|e| matches!(e, Event::Goal { .. }))
            .count(),
    })
}

/// An 8-bit RGB image (`pixels`: rows top to bottom) as a PNG file.
fn write_png(out: &Path, width: u32, height: u32, pixels: &[u8]) -> anyhow::Result<()> {
    let file = std::io::BufWriter::new(std::fs::File::create(out)?);
    let mut png = png::Encoder::new(file, width, height);
    png.set_color(png::ColorType::Rgb);
    png.set_depth(png::BitDepth::Eight);
    let mut png = png.write_header()?;
    png.write_image_data(pixels)?;
    png.finish()?;
    Ok(())
}

/// A path split where it jumps (a reset after a goal or an out): no body
/// moves 0.6 m in one tick, so such a step is a placement, not motion.
fn split_at_jumps(path: &[(f64, f64)]) -> impl Iterator<Item = &[(f64, f64)]> {
    let mut start = 0;
    let mut i = 1;
    std::iter::from_fn(move || {
        while i < path.len() {
            let (a, b) = (path[i - 1], path[i]);
            i += 1;
            if (a.0 - b.0).hypot(a.1 - b.1) > 0.6 {
                let seg = &path[start..i - 1];
                start = i - 1;
                return Some(seg);
            }
        }
        if start < path.len() {
            let seg = &path[start..];
            start = path.len();
            return Some(seg);
        }
        None
    })
}
