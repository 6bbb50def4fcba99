//! `naosoccer match`: a whole match in process; and `bench sim`, which times
//! one against the bare physics floor.
use std::io::{IsTerminal, Write};
use std::path::PathBuf;
use std::time::{Duration, Instant};

use anyhow::Context;
use clap::Args;
use naosoccer::live::{LiveServer, MatchStream, Pace};
use naosoccer_eval::run::{self, Fixture, MatchOutcome};
use naosoccer_policy::PolicyKind;
use naosoccer_proto::{Action, Event, Team, TeamStats, Tick, ROBOTS};

use super::team::TeamSpec;
use naosoccer_record::{MatchMeta, Recorder, RecorderOptions, RecordingSummary};
use naosoccer_referee::{Ending, Match, MatchConfig, Scenario};
use naosoccer_sim::{BareWorld, RobotModel};

#[derive(Args, Debug)]
#[command(after_help = "\
With --json, stdout holds exactly one JSON object:
  {\"seed\", \"ticks\", \"sim_seconds\", \"wall_seconds\",
   \"score\": {\"blue\", \"red\"},
   \"stats\": {\"blue\": {\"goals\", \"goals_open_play\", \"goals_restart\", \"goals_own_goal\",
     \"goals_disallowed\", \"control_rate\", \"passes\", \"aimed_passes\", \"shots\", \"falls\",
     \"out_of_bounds\", ...},
     \"red\": {...}},
   \"state_hash\"}
state_hash is the final match state's hash as 16 hex digits: the same seed,
config and policies give the same hash on the same build.

Statistics: control_rate is the share of the ticks in which any team controlled
the ball (the paper's if_c) that this team did; a pass is possession moving
between teammates after a kick by the first, aimed_passes those whose kick was
the action pass swung toward a receiver (not a shot a teammate happened to
reach); shots count every kick that moved the ball; out_of_bounds counts the team's robots that left the field and the
balls it put out (last touch). Goals by phase: goals_open_play,
goals_restart (from the team's own kick-off or set play: only its robots touched
the ball since, within 15 s) and goals_own_goal (the other team's own goals) sum
to goals; goals_disallowed counts goals straight from the team's kick-off, which
do not count (docs/PROTOCOL.md, \"Restarts and set plays\").")]
pub struct MatchArgs {
    /// Match seed: with the same config and policies, the same seed plays the
    /// same match (gait and kick noise, random policies).
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Match configuration (TOML; fields left out keep their defaults, see
    /// assets/match.toml).
    #[arg(long, value_name = "FILE")]
    config: Option<PathBuf>,
    /// Blue's policy, one instance per robot: scripted (the paper's
    /// rule-based team), a scripted variant (scripted:KEY=VAL,... or
    /// scripted:FILE.toml, e.g. scripted:assets/scripted/press.toml), random,
    /// idle, or a trained team (ppo:DIR, dqn:DIR,
    /// e.g. ppo:assets/policies/ppo-paper-seed1; docs/LEARNING.md)
    /// [default: scripted; with --scenario, the opponents' default is the
    /// scenario's `opponent`].
    #[arg(long, value_name = "POLICY")]
    blue: Option<String>,
    /// Red's policy: as --blue.
    #[arg(long, value_name = "POLICY")]
    red: Option<String>,
    /// Start from this scenario (docs/SCENARIOS.md) instead of the
    /// kick-off, drawn from --seed, and stop at its first end condition
    /// that holds or when its time is up; the output adds how it ended.
    /// With --record the recording stores the scenario and ends with it;
    /// `naosoccer replay` re-creates the start.
    #[arg(long, value_name = "FILE")]
    scenario: Option<PathBuf>,
    /// With --scenario: the colour the team under test (the file's own
    /// team, attacking +x in the file) plays.
    #[arg(long, value_name = "COLOUR", default_value = "blue",
          value_parser = ["blue", "red"], requires = "scenario")]
    own: String,
    /// Match length in minutes of game time (overrides the config).
    #[arg(long, value_name = "M")]
    minutes: Option<f32>,
    /// Print one JSON object instead of the table.
    #[arg(long)]
    json: bool,
    /// Record the match to this MCAP file (docs/RECORDINGS.md); `naosoccer
    /// replay FILE` re-simulates it.
    #[arg(long, value_name = "FILE.mcap")]
    record: Option<PathBuf>,
    /// Stream the match live to Foxglove (Foxglove WebSocket,
    /// topics /match/1/...; docs/RECORDINGS.md) on ADDR, default
    /// 127.0.0.1:8765 (port 0: any free port, printed on stderr), and play it
    /// at real-time pace (see --speed).
    #[arg(long, value_name = "ADDR", num_args = 0..=1,
          default_missing_value = naosoccer::live::DEFAULT_ADDR)]
    pub live: Option<String>,
    /// With --live: game seconds per second of wall-clock time (1 = real
    /// time, 4 = four times as fast).
    #[arg(long, value_name = "X", default_value_t = 1.0, requires = "live")]
    speed: f64,
    /// With --live: wait for a viewer to subscribe to the scene before
    /// kick-off (at most 10 minutes).
    #[arg(long, requires = "live")]
    wait_viewer: bool,
}

impl MatchArgs {
    /// The policies as resolved by `run` (defaults filled in).
    fn blue(&self) -> &str {
        self.blue.as_deref().unwrap_or("scripted")
    }

    fn red(&self) -> &str {
        self.red.as_deref().unwrap_or("scripted")
    }
}

fn load_config(path: Option<&PathBuf>, minutes: Option<f32>) -> anyhow::Result<MatchConfig> {
    let mut cfg = match path {
        Some(p) => MatchConfig::from_file(p)?,
        None => MatchConfig::default(),
    };
    if let Some(m) = minutes {
        cfg.minutes = m;
        cfg.validate().context("--minutes")?;
    }
    Ok(cfg)
}

pub fn run(mut args: MatchArgs) -> anyhow::Result<()> {
    let cfg = load_config(args.config.as_ref(), args.minutes)?;
    let own = if args.own == "red" {
        Team::Red
    } else {
        Team::Blue
    };
    let scenario = match &args.scenario {
        Some(path) => {
            let s = Scenario::from_file(path)?;
            s.check(&cfg)
                .with_context(|| format!("{} against the match configuration", path.display()))?;
            Some(s)
        }
        None => None,
    };
    // The opponents of a scenario play its `opponent` unless named here.
    let default_of = |team: Team| match &scenario {
        Some(s) if team != own => s.opponent.clone(),
        _ => "scripted".to_owned(),
    };
    args.blue = Some(args.blue.take().unwrap_or_else(|| default_of(Team::Blue)));
    args.red = Some(args.red.take().unwrap_or_else(|| default_of(Team::Red)));
    let blue = TeamSpec::parse(args.blue(), "--blue")?;
    let red = TeamSpec::parse(args.red(), "--red")?;
    let new_match = |cfg: &MatchConfig, seed: u64| match &scenario {
        Some(s) => Match::with_scenario(cfg, seed, s, own),
        None => Match::new(cfg, seed),
    };
    // The match as it starts: the configuration and the scenario are
    // checked here, before anything is played or recorded.
    let start = new_match(&cfg, args.seed)?;
    let mut ending: Option<Ending> = None;
    let mut first = blue.side()?;
    let mut second = red.side()?;
    let fixture = Fixture {
        scenario: scenario.as_ref().map(|s| (s, own)),
        ..Fixture::kick_off(args.seed)
    };
    let show_progress = std::io::stdout().is_terminal();
    let mut last_shown = Tick::ZERO;
    // From here on Ctrl-C ends the match after the current tick and keeps it.
    naosoccer::interrupt::watch()?;
    let mut recording = match &args.record {
        Some(path) => Some(MatchRecording::start(path, &args, &start)?),
        None => None,
    };
    let mut live = match &args.live {
        Some(addr) => Some(LiveMatch::start(
            addr,
            &cfg,
            &args,
            new_match(&cfg, args.seed)?,
        )?),
        None => None,
    };
    // Ctrl-C before the end: the match's length in ticks, for the report.
    let mut cut_short: Option<u64> = None;
    let outcome = run::play_one(&cfg, &mut first, &mut second, fixture, |t| {
        let (m, actions, events) = (t.m, t.actions, t.events);
        // A scenario's end is the runner's to find; it is the match's last
        // tick.
        ending = t.ending;
        // Ctrl-C: this tick is the last; the recording is finished with
        // it (its final statistics say the match was not completed).
        let stop = naosoccer::interrupt::interrupted() && !m.is_finished();
        if stop {
            cut_short = Some(m.total_ticks());
        }
        if let Some(r) = &mut recording {
            // A scenario's ending is the recording's last tick too.
            r.tick(m, actions, events, stop || ending.is_some());
        }
        if let Some(l) = &mut live {
            l.tick(m, events);
        }
        // About once a game minute; enough to see it move, cheap to print.
        if show_progress && (m.tick() - last_shown >= 600 || m.is_finished()) {
            last_shown = m.tick();
            let naosoccer_proto::PerTeam { blue: b, red: r } = m.score();
            let mut err = std::io::stderr().lock();
            let _ = write!(
                err,
                "\r{:>5.1}/{:.1} min  blue {b} - {r} red ",
                m.sim_seconds() / 60.0,
                m.total_ticks() as f64 / f64::from(cfg.control_hz) / 60.0
            );
            if m.is_finished() {
                let _ = writeln!(err);
            }
        }
        if stop {
            std::ops::ControlFlow::Break(())
        } else {
            std::ops::ControlFlow::Continue(())
        }
    })?;

    if let Some(l) = live {
        l.server.finish(naosoccer::live::LINGER);
    }
    let recorded = match recording {
        Some(r) => Some(r.report()?),
        None => None,
    };
    let ended = scenario.as_ref().zip(ending).map(|(s, e)| {
        serde_json::json!({
            "name": s.name,
            "own": own.to_string(),
            "ending": e.kind.name(),
            "success": e.success,
            "ticks": e.ticks,
            "seconds": e.ticks as f64 / f64::from(cfg.control_hz),
        })
    });
    if args.json {
        let mut json = outcome.to_json();
        if let Some(e) = &ended {
            json["scenario"] = e.clone();
        }
        if let Some(r) = &recorded {
            json["recording"] = serde_json::to_value(r)?;
        }
        println!("{json}");
    } else {
        print_table(&args, &outcome);
        if let Some(e) = &ended {
            println!(
                "scenario {} (own team {}): {} after {:.1} s, a {}",
                e["name"].as_str().unwrap_or_default(),
                e["own"].as_str().unwrap_or_default(),
                e["ending"].as_str().unwrap_or_default(),
                e["seconds"].as_f64().unwrap_or_default(),
                if e["success"] == true {
                    "success"
                } else {
                    "failure"
                }
            );
        }
        if let Some(r) = &recorded {
            println!("recorded to {} ({} bytes)", r.path.display(), r.bytes);
        }
    }
    if let Some(total) = cut_short {
        return Err(naosoccer::interrupt::Interrupted::new(format!(
            "the match stopped at tick {} of {total}; the results above are of the match so far{}",
            outcome.ticks,
            if recorded.is_some() {
                ", and the recording is finished and readable (marked not completed)"
            } else {
                ""
            }
        ))
        .into());
    }
    Ok(())
}

/// `--live`: the match streamed at real-time pace.
struct LiveMatch {
    server: LiveServer,
    stream: MatchStream,
    pace: Pace,
}

impl LiveMatch {
    fn start(addr: &str, cfg: &MatchConfig, args: &MatchArgs, m: Match) -> anyhow::Result<Self> {
        anyhow::ensure!(
            args.speed > 0.0 && args.speed.is_finite(),
            "--speed must be a positive number"
        );
        let server = LiveServer::start(addr)?;
        let mut stream = server.stream(1)?;
        // The same seed, config and scenario give the runner's start.
        stream.begin(&m);
        if args.wait_viewer && !server.wait_for_viewer(Duration::from_secs(600)) {
            anyhow::bail!("no viewer subscribed within 10 minutes");
        }
        stream.tick_of(&m, &[], true);
        Ok(LiveMatch {
            server,
            stream,
            pace: Pace::new(cfg.control_hz, args.speed),
        })
    }

    fn tick(&mut self, m: &Match, events: &[Event]) {
        if self.stream.watched() {
            let with_stats = m.tick().get().is_multiple_of(10) || m.is_finished();
            self.stream.tick_of(m, events, with_stats);
        }
        self.pace.wait(m.tick().get());
    }
}

/// `--record`: the recorder of an in-process match. The runner owns the
/// match, so the recording is finished from the last tick's callback.
struct MatchRecording {
    path: PathBuf,
    rec: Option<Recorder>,
    summary: Option<RecordingSummary>,
    error: Option<anyhow::Error>,
}

#[derive(serde::Serialize)]
struct RecordingReport {
    path: PathBuf,
    bytes: u64,
    messages: std::collections::BTreeMap<String, u64>,
}

impl MatchRecording {
    /// `m`: the match about to be played, at its start.
    fn start(path: &std::path::Path, args: &MatchArgs, m: &Match) -> anyhow::Result<Self> {
        let meta = MatchMeta::of(m, args.blue(), args.red(), "match");
        let rec = Recorder::create(path, &meta, m, RecorderOptions::default())
            .with_context(|| format!("creating {}", path.display()))?;
        Ok(MatchRecording {
            path: path.to_owned(),
            rec: Some(rec),
            summary: None,
            error: None,
        })
    }

    /// Records one tick; with `last` (Ctrl-C) or at the match's end also
    /// finishes the recording.
    fn tick(&mut self, m: &Match, actions: &[Action; ROBOTS], events: &[Event], last: bool) {
        let Some(rec) = &mut self.rec else { return };
        let r = rec.tick(m, actions, events);
        let r = r.and_then(|()| {
            if m.is_finished() || last {
                let rec = self.rec.take().expect("recorder present");
                self.summary = Some(rec.finish(m)?.0);
            }
            Ok(())
        });
        if let Err(e) = r {
            self.rec = None;
            self.error = Some(
                anyhow::Error::new(e).context(format!("recording to {}", self.path.display())),
            );
        }
    }

    fn report(self) -> anyhow::Result<RecordingReport> {
        if let Some(e) = self.error {
            return Err(e);
        }
        let summary = self
            .summary
            .context("the match ended before the recording was finished")?;
        let bytes = std::fs::metadata(&self.path)?.len();
        Ok(RecordingReport {
            path: self.path,
            bytes,
            messages: summary.messages,
        })
    }
}

fn print_table(args: &MatchArgs, o: &MatchOutcome) {
    println!(
        "naosoccer match: seed {}, {} (blue) vs {} (red)",
        o.seed,
        args.blue(),
        args.red()
    );
    println!("final score: blue {} - {} red", o.score.blue, o.score.red);
    println!();
    println!("{:<16}{:>10}{:>10}", "", "blue", "red");
    let row = |name: &str, f: &dyn Fn(&TeamStats) -> String| {
        println!(
            "{:<16}{:>10}{:>10}",
            name,
            f(&o.stats.blue),
            f(&o.stats.red)
        );
    };
    row("goals", &|t| t.goals.to_string());
    row("  open play", &|t| t.goals_open_play.to_string());
    row("  own restarts", &|t| t.goals_restart.to_string());
    row("  own goals for", &|t| t.goals_own_goal.to_string());
    row("disallowed", &|t| t.goals_disallowed.to_string());
    row("ball control", &|t| {
        format!("{:.1}%", 100.0 * t.control_rate)
    });
    row("passes", &|t| t.passes.to_string());
    row("  aimed", &|t| t.aimed_passes.to_string());
    row("shots", &|t| t.shots.to_string());
    row("falls", &|t| t.falls.to_string());
    row("out of bounds", &|t| t.out_of_bounds.to_string());
    println!();
    println!(
        "{} ticks, {:.1} s of game time in {:.2} s ({:.0}x real time), {} events; state hash {:016x}",
        o.ticks,
        o.sim_seconds,
        o.wall_seconds,
        o.sim_seconds / o.wall_seconds.max(1e-9),
        o.events,
        o.state_hash
    );
}

#[derive(Args, Debug)]
pub struct BenchSimArgs {
    /// Seed of the timed match.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Match configuration (TOML); the default is assets/match.toml.
    #[arg(long, value_name = "FILE")]
    config: Option<PathBuf>,
    /// Match length in minutes of game time (overrides the config).
    #[arg(long, value_name = "M")]
    minutes: Option<f32>,
}

pub fn bench_sim(args: BenchSimArgs) -> anyhow::Result<()> {
    let cfg = load_config(args.config.as_ref(), args.minutes)?;
    if cfg!(debug_assertions) {
        eprintln!(
            "warning: a debug build; run `cargo run --release -- bench sim` for real figures"
        );
    }
    // The match decides how many physics steps the floor takes.
    let probe = Match::new(&cfg, args.seed)?;
    let steps = probe.total_ticks() * u64::from(probe.steps_per_tick());
    let dt = probe.sim().dt();
    drop(probe);
    let game_seconds = steps as f64 * f64::from(dt);

    let model = RobotModel::builtin()?;
    let mut bare = BareWorld::new(&cfg.sim, &model)?;
    let start = Instant::now();
    for _ in 0..steps {
        bare.step();
    }
    let floor = start.elapsed().as_secs_f64();

    let scripted = PolicyKind::Scripted;
    let outcome = run::play_match(&cfg, args.seed, &scripted, &scripted, |_| {})?;
    let full = outcome.wall_seconds;

    println!(
        "bench sim: {steps} physics steps of {:.4} s = {:.0} s of game time ({} ticks at {} Hz)",
        dt, game_seconds, outcome.ticks, cfg.control_hz
    );
    println!(
        "{:<44}{:>10}{:>14}{:>14}",
        "", "wall s", "steps/s", "x real time"
    );
    let line = |name: &str, secs: f64| {
        println!(
            "{:<44}{:>10.3}{:>14.0}{:>14.0}",
            name,
            secs,
            steps as f64 / secs.max(1e-9),
            game_seconds / secs.max(1e-9)
        );
    };
    // The same match again, recorded to MCAP in memory (what `--record`
    // and the server add); `m` is its start, the recording's first state.
    let m = Match::new(&cfg, args.seed)?;
    let meta = MatchMeta::of(&m, &scripted.to_string(), &scripted.to_string(), "match");
    // The recorder's own time (start, every tick, finish), apart from the
    // match's: the write time of the recording.
    let mut writing = Instant::now();
    let mut rec = Some(Recorder::in_memory(&meta, &m, RecorderOptions::default())?);
    let mut write_time = writing.elapsed();
    let opening = write_time.as_secs_f64();
    let mut bytes = 0;
    let recorded = run::play_match(&cfg, args.seed, &scripted, &scripted, |t| {
        if let Some(r) = &mut rec {
            writing = Instant::now();
            r.tick(t.m, t.actions, t.events)
                .expect("recording to memory");
            if t.m.is_finished() {
                let (_, sink) = rec
                    .take()
                    .unwrap()
                    .finish(t.m)
                    .expect("finishing in memory");
                bytes = sink.into_bytes().map_or(0, |b| b.len());
            }
            write_time += writing.elapsed();
        }
    })?;
    // The match with its recording, the recorder's start included.
    let with_recording = opening + recorded.wall_seconds;
    anyhow::ensure!(
        recorded.state_hash == outcome.state_hash,
        "recording changed the match (state hash {:016x} vs {:016x})",
        recorded.state_hash,
        outcome.state_hash
    );

    line("bare rapier floor (same bodies, bare driving)", floor);
    line("full match (physics+referee+scripted x8)", full);
    line("full match, recorded to MCAP", with_recording);
    println!("match / floor: {:.2}x", full / floor.max(1e-9));
    println!(
        "recording overhead: {:+.1}% ({:.1} MB for the match)",
        100.0 * (with_recording / full.max(1e-9) - 1.0),
        bytes as f64 / 1e6
    );
    println!(
        "recorder's own time: {:.3} s ({:.1} us a tick), {bytes} bytes",
        write_time.as_secs_f64(),
        1e6 * write_time.as_secs_f64() / outcome.ticks.max(1) as f64
    );
    println!(
        "match result: blue {} - {} red, state hash {:016x}",
        outcome.score.blue, outcome.score.red, outcome.state_hash
    );
    Ok(())
}
