//! `naosoccer replay` and `naosoccer render`: recordings after the fact.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::Context;
use clap::Args;
use naosoccer_proto::{Event, Team, Tick};
use naosoccer_record::{replay, Recording, ReplayOutcome};

use naosoccer_render::{render_png, write_gif, GifOptions};

#[derive(Args, Debug)]
#[command(
    after_help = "Exit codes: 0 every recorded tick was reproduced bit for bit; \
1 a tick differs (the first one is printed with both states); \
2 identical as far as it goes, but the recording was cut short; \
3 the file could not be read as a naosoccer recording."
)]
pub struct ReplayArgs {
    /// The recording (.mcap) to re-simulate.
    pub file: PathBuf,
    /// Print the match statistics stored in the file instead of re-simulating.
    #[arg(long)]
    pub summary: bool,
    /// First stream the recording live to Foxglove (Foxglove
    /// WebSocket on ADDR, default 127.0.0.1:8765; topics /match/ID/..., ID
    /// the recorded server match id or 1), every recorded tick in order at
    /// real-time pace (see --speed); then re-simulate and check as usual.
    #[arg(long, value_name = "ADDR", num_args = 0..=1,
          default_missing_value = naosoccer::live::DEFAULT_ADDR)]
    pub live: Option<String>,
    /// With --live: game seconds per second of wall-clock time.
    #[arg(long, value_name = "X", default_value_t = 1.0, requires = "live")]
    pub speed: f64,
    /// With --live: wait for a viewer to subscribe to the scene first (at
    /// most 10 minutes).
    #[arg(long, requires = "live")]
    pub wait_viewer: bool,
}

#[derive(Args, Debug)]
#[command(
    group = clap::ArgGroup::new("output").required(true).multiple(true).args(["out", "gif"]),
    after_help = "--out draws the whole match in one PNG: the paths of the ball and \
the robots, goals ringed. --gif draws it as an animated top view: the pitch, \
robots (team colours, one shade per player, a black heading line, a grey centre \
when fallen, a yellow ring on the robot in possession) and the ball, under a \
banner with the score (blue - red) and the game clock. Every frame shows one \
tick; --speed game seconds pass per second of GIF at --fps frames per second, \
so frames are --speed x control rate / --fps ticks apart (at 10 Hz, the \
defaults --speed 10 --fps 10 draw every 10th tick: a 10-minute match in 60 s, \
601 frames). --from/--to cut a part of the match."
)]
pub struct RenderArgs {
    /// The recording (.mcap) to draw.
    pub file: PathBuf,
    /// Where to write the PNG (a still: the whole match's paths).
    #[arg(long, short, value_name = "OUT.png")]
    pub out: Option<PathBuf>,
    /// Where to write an animated GIF of the match (top view, score, clock).
    #[arg(long, value_name = "OUT.gif")]
    pub gif: Option<PathBuf>,
    /// Image width in pixels (the height follows the pitch's proportions);
    /// default 1400 for the PNG, 480 for the GIF.
    #[arg(long)]
    pub width: Option<u32>,
    /// GIF: game seconds per second of animation.
    #[arg(long, default_value_t = 10.0, value_name = "S")]
    pub speed: f64,
    /// GIF: frames per second of animation (1 to 50).
    #[arg(long, default_value_t = 10, value_name = "N")]
    pub fps: u32,
    /// GIF: start at this game time (seconds).
    #[arg(long, default_value_t = 0.0, value_name = "SECONDS")]
    pub from: f64,
    /// GIF: stop at this game time (seconds; default: the end).
    #[arg(long, value_name = "SECONDS")]
    pub to: Option<f64>,
}

pub fn replay_cmd(args: ReplayArgs) -> ExitCode {
    let rec = match Recording::read_file(&args.file) {
        Ok(r) => r,
        Err(e) => {
            eprintln!("error: {}: {e}", args.file.display());
            return ExitCode::from(3);
        }
    };
    if let Some(addr) = &args.live {
        if let Err(e) = stream_recording(&rec, addr, &args) {
            eprintln!("error: {}", crate::cmd::error_text(&e));
            return ExitCode::from(3);
        }
    }
    if args.summary {
        print_summary(&rec);
        return if rec.is_complete() {
            ExitCode::SUCCESS
        } else {
            ExitCode::from(2)
        };
    }
    match replay(&rec) {
        Ok(ReplayOutcome::Identical { ticks, truncated }) => {
            if truncated {
                println!(
                    "identical ({ticks} ticks), but the recording was cut short: {}",
                    rec.truncated
                        .as_deref()
                        .unwrap_or("it has no final statistics")
                );
                ExitCode::from(2)
            } else {
                println!("identical ({ticks} ticks)");
                ExitCode::SUCCESS
            }
        }
        Ok(ReplayOutcome::Diverged {
            tick,
            recorded,
            replayed,
        }) => {
            println!("differs at tick {tick}");
            let pretty = |s: &naosoccer_record::StateRecord| {
                serde_json::to_string_pretty(s).unwrap_or_else(|e| e.to_string())
            };
            let (a, b) = (pretty(&recorded), pretty(&replayed));
            println!("{:<60} | replayed", "recorded");
            for (l, r) in a.lines().zip(b.lines()) {
                let mark = if l == r { ' ' } else { '*' };
                println!("{l:<60} |{mark}{r}");
            }
            ExitCode::from(1)
        }
        Err(e) => {
            eprintln!("error: {}: {e}", args.file.display());
            ExitCode::from(3)
        }
    }
}

/// `replay --live`: every recorded state in order, with the events up to
/// it, at the chosen pace; the final statistics at the end.
fn stream_recording(rec: &Recording, addr: &str, args: &ReplayArgs) -> anyhow::Result<()> {
    use naosoccer::live::{LiveServer, Pace, LINGER};
    anyhow::ensure!(
        args.speed > 0.0 && args.speed.is_finite(),
        "--speed must be a positive number"
    );
    let server = LiveServer::start(addr)?;
    let mut stream = server.stream(rec.meta.match_id.unwrap_or(1))?;
    // The scene's geometry comes from the recorded configuration, the
    // scoreboard's name from the recorded scenario.
    let m = naosoccer_record::recorded_start(rec).context("re-creating the recorded match")?;
    stream.begin(&m);
    if args.wait_viewer && !server.wait_for_viewer(std::time::Duration::from_secs(600)) {
        anyhow::bail!("no viewer subscribed within 10 minutes");
    }
    let pace = Pace::new(rec.meta.control_hz, args.speed);
    let mut events = rec.events.iter().peekable();
    let mut due = Vec::new();
    let first = rec.states.first().map_or(Tick::ZERO, |s| s.tick);
    for (i, state) in rec.states.iter().enumerate() {
        due.clear();
        while let Some(e) = events.next_if(|e| e.tick().is_none_or(|t| t <= state.tick)) {
            due.push(e.clone());
        }
        let last = i + 1 == rec.states.len();
        let stats = if last {
            rec.stats.as_ref().map(|f| f.stats)
        } else {
            None
        };
        pace.wait(state.tick - first);
        stream.tick(state, &due, stats.as_ref());
    }
    server.finish(LINGER);
    Ok(())
}

fn print_summary(rec: &Recording) {
    let m = &rec.meta;
    println!(
        "naosoccer recording (format {}, naosoccer {}), source {}{}",
        m.format,
        m.naosoccer_version,
        m.source,
        m.match_id
            .map(|id| format!(", match {id}"))
            .unwrap_or_default()
    );
    println!(
        "seed {}, blue: {}, red: {}, {} ticks planned at {} Hz",
        m.seed, m.blue, m.red, m.total_ticks, m.control_hz
    );
    if let Some(s) = &m.scenario {
        println!("started from scenario {} (own team {})", s.name, s.own);
    }
    match &rec.stats {
        Some(f) => {
            println!(
                "final score: blue {} - {} red after {} ticks{}",
                f.score.blue,
                f.score.red,
                f.ticks,
                if f.completed { "" } else { " (stopped early)" }
            );
            println!(
                "{:<6} {:>6} {:>10} {:>8} {:>9} {:>11} {:>8} {:>7} {:>6} {:>6} {:>6} {:>5}",
                "team",
                "goals",
                "open play",
                "restart",
                "own goal",
                "disallowed",
                "control",
                "passes",
                "aimed",
                "shots",
                "falls",
                "outs"
            );
            for team in Team::BOTH {
                let s = f.stats.team(team);
                println!(
                    "{:<6} {:>6} {:>10} {:>8} {:>9} {:>11} {:>7.1}% {:>7} {:>6} {:>6} {:>6} {:>5}",
                    team.to_string(),
                    s.goals,
                    s.goals_open_play,
                    s.goals_restart,
                    s.goals_own_goal,
                    s.goals_disallowed,
                    100.0 * s.control_rate,
                    s.passes,
                    s.aimed_passes,
                    s.shots,
                    s.falls,
                    s.out_of_bounds
                );
            }
        }
        None => println!(
            "no final statistics: the recording was cut short after {} ticks ({})",
            rec.actions.len(),
            rec.truncated.as_deref().unwrap_or("no summary")
        ),
    }
    let goals = rec
        .events
        .iter()
        .filter(|e| matches!(e, Event::Goal { .. }))
        .count();
    println!("{} events ({} goals)", rec.events.len(), goals);
    for (topic, n) in &rec.counts {
        println!("  {topic:<18} {n:>7} messages");
    }
}

pub fn render_cmd(args: RenderArgs) -> anyhow::Result<()> {
    let rec = Recording::read_file(&args.file)
        .with_context(|| format!("reading {}", args.file.display()))?;
    if let Some(why) = &rec.truncated {
        eprintln!("warning: the recording was cut short ({why}); drawing what it holds");
    }
    if let Some(out) = &args.out {
        let s = render_png(&rec, out, args.width.unwrap_or(1400))?;
        println!(
            "wrote {} ({} ticks, {} goals)",
            out.display(),
            s.ticks,
            s.goals
        );
    }
    if let Some(out) = &args.gif {
        let opts = GifOptions {
            width: args.width.unwrap_or(480),
            speed: args.speed,
            fps: args.fps,
            from: args.from,
            to: args.to,
        };
        let s = write_gif(&rec, out, opts)?;
        let hz = rec.meta.control_hz as f64;
        println!(
            "wrote {} ({} frames of {}x{}, every {} ticks, game time {:.1}-{:.1} s, {} fps)",
            out.display(),
            s.frames,
            s.width,
            s.height,
            s.step,
            s.first_tick.get() as f64 / hz,
            s.last_tick.get() as f64 / hz,
            args.fps
        );
    }
    Ok(())
}
