//! Training curves in the style of the paper's Figures 4-6: the long-term
//! average reward (the running mean of the per-robot reward since the start
//! of training) against timeslots (control ticks per match), for the team and
//! for each robot, several runs (e.g. DQN and PPO) on one chart.

use std::path::{Path, PathBuf};

use plotters::prelude::*;

use crate::LearnError;

/// One run's curves, read from its `metrics.csv`.
#[derive(Debug, Clone, PartialEq)]
pub struct Curves {
    pub label: String,
    pub timeslot: Vec<f64>,
    /// Long-term average reward of the team (mean over learning robots).
    pub team: Vec<f64>,
    /// Per robot: (player, long-term average reward).
    pub robots: Vec<(usize, Vec<f64>)>,
}

/// Reads a run directory (or a metrics CSV) into its running-average curves.
pub fn read_run(path: &Path) -> Result<Curves, LearnError> {
    let (csv, dir) = if path.is_dir() {
        (path.join("metrics.csv"), path.to_path_buf())
    } else {
        (
            path.to_path_buf(),
            path.parent().map(Path::to_path_buf).unwrap_or_default(),
        )
    };
    let text = std::fs::read_to_string(&csv).map_err(|e| LearnError::io(&csv, e))?;
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap_or_default().split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name);
    let bad = |what: String| LearnError::Plot(format!("{}: {what}", csv.display()));
    let (Some(ts), Some(tr), Some(rw)) = (col("timeslot"), col("transitions"), col("reward"))
    else {
        return Err(bad(
            "not a naosoccer metrics.csv (no timeslot/transitions/reward columns)".into(),
        ));
    };
    let robot_cols: Vec<(usize, usize)> = header
        .iter()
        .enumerate()
        .filter_map(|(i, h)| {
            h.strip_prefix("reward_p")
                .and_then(|p| p.parse().ok())
                .map(|p| (p, i))
        })
        .collect();
    let algo = std::fs::read_to_string(dir.join("config.json"))
        .ok()
        .and_then(|j| serde_json::from_str::<serde_json::Value>(&j).ok())
        .and_then(|v| {
            v.get("algo")
                .and_then(|a| a.as_str())
                .map(str::to_uppercase)
        });
    let name = dir
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let label = match algo {
        Some(a) => format!("{a} ({name})"),
        None => name,
    };
    let mut c = Curves {
        label,
        timeslot: Vec::new(),
        team: Vec::new(),
        robots: robot_cols.iter().map(|&(p, _)| (p, Vec::new())).collect(),
    };
    let (mut prev_tr, mut weight) = (0.0, 0.0);
    let mut sums = vec![0.0; robot_cols.len() + 1];
    for (n, line) in lines.enumerate() {
        let f: Vec<&str> = line.split(',').collect();
        let num = |i: usize| -> Result<f64, LearnError> {
            f.get(i)
                .and_then(|v| v.parse::<f64>().ok())
                .ok_or_else(|| bad(format!("line {}: bad number in column {}", n + 2, i + 1)))
        };
        let t = num(tr)?;
        let w = (t - prev_tr).max(0.0);
        prev_tr = t;
        weight += w;
        sums[0] += w * num(rw)?;
        for (k, &(_, i)) in robot_cols.iter().enumerate() {
            sums[k + 1] += w * num(i)?;
        }
        if weight <= 0.0 {
            continue;
        }
        c.timeslot.push(num(ts)?);
        c.team.push(sums[0] / weight);
        for (k, r) in c.robots.iter_mut().enumerate() {
            r.1.push(sums[k + 1] / weight);
        }
    }
    if c.timeslot.is_empty() {
        return Err(bad("no metric rows yet".into()));
    }
    Ok(c)
}

const COLOURS: [RGBColor; 6] = [
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
    RGBColor(148, 103, 189),
    RGBColor(255, 127, 14),
    RGBColor(23, 190, 207),
];

/// Draws the team chart (left) and the per-robot chart (right) for `runs`
/// into a PNG at `out`.
pub fn plot_runs(runs: &[PathBuf], out: &Path) -> Result<(), LearnError> {
    let curves = runs
        .iter()
        .map(|r| read_run(r))
        .collect::<Result<Vec<_>, _>>()?;
    draw(&curves, out).map_err(|e| LearnError::Plot(e.to_string()))
}

fn range(vals: impl Iterator<Item = f64>) -> (f64, f64) {
    let (lo, hi) = vals
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
            (a.min(v), b.max(v))
        });
    if !lo.is_finite() {
        return (0.0, 1.0);
    }
    let pad = ((hi - lo) * 0.05).max(1e-3);
    (lo - pad, hi + pad)
}

/// Figure size: two charts side by side, the legend in a strip below them
/// (never over a curve).
const WIDTH: u32 = 1400;
const CHART_HEIGHT: u32 = 560;
const LEGEND_COLUMNS: usize = 3;
const LEGEND_ROW: i32 = 24;

fn draw(curves: &[Curves], out: &Path) -> Result<(), Box<dyn std::error::Error>> {
    let rows = curves.len().div_ceil(LEGEND_COLUMNS) as i32;
    // The runs' rows, then one line explaining the per-robot widths.
    let legend_height = (16 + (rows + 1) * LEGEND_ROW) as u32;
    let root = BitMapBackend::new(out, (WIDTH, CHART_HEIGHT + legend_height)).into_drawing_area();
    root.fill(&WHITE)?;
    let (charts, legend) = root.split_vertically(CHART_HEIGHT);
    let (left, right) = charts.split_horizontally(WIDTH / 2);
    let xmax = curves
        .iter()
        .flat_map(|c| c.timeslot.iter().copied())
        .fold(1.0, f64::max);
    let whole = |x: &f64| format!("{x:.0}");

    let (lo, hi) = range(curves.iter().flat_map(|c| c.team.iter().copied()));
    let mut chart = ChartBuilder::on(&left)
        .caption("Team: long-term average reward", ("sans-serif", 22))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(60)
        .build_cartesian_2d(0.0..xmax, lo..hi)?;
    chart
        .configure_mesh()
        .x_desc("timeslot (control ticks per match)")
        .y_desc("average reward per robot and tick")
        .x_label_formatter(&whole)
        .draw()?;
    for (i, c) in curves.iter().enumerate() {
        let colour = COLOURS[i % COLOURS.len()];
        chart.draw_series(LineSeries::new(
            c.timeslot.iter().copied().zip(c.team.iter().copied()),
            colour.stroke_width(2),
        ))?;
    }

    let (lo, hi) = range(
        curves
            .iter()
            .flat_map(|c| c.robots.iter().flat_map(|r| r.1.iter().copied())),
    );
    let mut chart = ChartBuilder::on(&right)
        .caption("Per robot: long-term average reward", ("sans-serif", 22))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(60)
        .build_cartesian_2d(0.0..xmax, lo..hi)?;
    chart
        .configure_mesh()
        .x_desc("timeslot (control ticks per match)")
        .y_desc("average reward per tick")
        .x_label_formatter(&whole)
        .draw()?;
    for (i, c) in curves.iter().enumerate() {
        let colour = COLOURS[i % COLOURS.len()];
        for (k, (_, r)) in c.robots.iter().enumerate() {
            chart.draw_series(LineSeries::new(
                c.timeslot.iter().copied().zip(r.iter().copied()),
                robot_style(colour, k),
            ))?;
        }
    }

    // The legend: one entry per run (its colour in both charts).
    let font = ("sans-serif", 16).into_font();
    let column = (WIDTH as usize / LEGEND_COLUMNS) as i32;
    for (i, c) in curves.iter().enumerate() {
        let colour = COLOURS[i % COLOURS.len()];
        let x = 24 + (i % LEGEND_COLUMNS) as i32 * column;
        let y = 16 + (i / LEGEND_COLUMNS) as i32 * LEGEND_ROW;
        legend.draw(&PathElement::new(
            vec![(x, y), (x + 32, y)],
            colour.stroke_width(3),
        ))?;
        legend.draw(&Text::new(c.label.clone(), (x + 40, y - 8), font.clone()))?;
    }
    let y = 16 + rows * LEGEND_ROW;
    let mut x = 24;
    legend.draw(&Text::new(
        "Per robot: one line each, in its run's colour, robot",
        (x, y - 8),
        font.clone(),
    ))?;
    x += 400;
    let max_robots = curves.iter().map(|c| c.robots.len()).max().unwrap_or(0);
    for k in 0..max_robots {
        let player = curves
            .iter()
            .find_map(|c| c.robots.get(k).map(|r| r.0))
            .unwrap_or(k);
        legend.draw(&PathElement::new(
            vec![(x, y), (x + 32, y)],
            robot_style(COLOURS[0], k),
        ))?;
        legend.draw(&Text::new(
            format!("{player}"),
            (x + 38, y - 8),
            font.clone(),
        ))?;
        x += 70;
    }
    root.present()?;
    Ok(())
}

/// Robots of one run share its colour; width and shade tell them apart.
fn robot_style(colour: RGBColor, k: usize) -> ShapeStyle {
    colour.mix(1.0 - 0.18 * k as f64).stroke_width(1 + k as u32)
}
