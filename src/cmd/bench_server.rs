//! `naosoccer bench server`: the match server measured from outside, as
//! clients see it (lockstep ticks a second, many matches at once, real-time
//! lateness), and with a Foxglove viewer watching.
use clap::Args;
use naosoccer_proto::msg::Mode;
use naosoccer_server::{Hooks, MatchObserver, ServerConfig, TickRecord};
use std::sync::Arc;
use tokio::net::TcpListener;

use super::server::{init_logging, with_live};

/// `naosoccer bench server`.
#[derive(Args, Debug)]
pub struct BenchServerArgs {
    /// Length of the single lockstep match, minutes of game time.
    #[arg(long, default_value_t = 10.0)]
    pub minutes: f32,
    /// Lockstep matches played at once in the second part.
    #[arg(long, default_value_t = 32)]
    pub concurrent: u32,
    /// Length of each of those matches, minutes.
    #[arg(long, default_value_t = 1.0)]
    pub concurrent_minutes: f32,
    /// Real-time matches at once in the third part.
    #[arg(long, default_value_t = 16)]
    pub realtime: u32,
    /// Wall-clock seconds the real-time matches run.
    #[arg(long, default_value_t = 20.0)]
    pub realtime_seconds: f32,
    /// Parts to run, comma-separated.
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "single,concurrent,realtime",
        value_name = "single|concurrent|realtime"
    )]
    pub parts: Vec<String>,
    /// Also play the single lockstep match with `--live` on and a Foxglove
    /// viewer connected that subscribes to all its channels (the scene
    /// among them) and reads everything, alternating with unwatched rounds
    /// (`--viewer-rounds` of each), and print every round's figures and
    /// the slowdown of the medians.
    #[arg(long)]
    pub viewer: bool,
    /// Rounds of each, unwatched and watched, with `--viewer`.
    #[arg(long, default_value_t = 3, value_parser = clap::value_parser!(u32).range(1..))]
    pub viewer_rounds: u32,
}

struct Latencies(std::sync::Mutex<Vec<std::time::Duration>>);

/// Collects the server's real-time tick lateness through the observer hook.
struct LatencyObserver(Arc<Latencies>);

impl MatchObserver for LatencyObserver {
    fn on_start(&mut self, _: &naosoccer_proto::msg::MatchInfo, _: &naosoccer_referee::Match) {}
    fn on_tick(&mut self, rec: &TickRecord<'_>) {
        if let Some(l) = rec.lateness {
            self.0 .0.lock().expect("bench lock").push(l);
        }
    }
    fn on_end(&mut self, _: &naosoccer_proto::msg::MatchEnd, _: &naosoccer_referee::Match) {}
}

/// What the bench's viewer received.
#[derive(Debug, Default)]
struct Watched {
    messages: u64,
    scenes: u64,
    bytes: u64,
}

/// A Foxglove viewer of `live`'s match 1, subscribed to all its channels,
/// reading until `stop`.
async fn bench_viewer(
    addr: String,
    stop: tokio::sync::oneshot::Receiver<()>,
) -> anyhow::Result<Watched> {
    use naosoccer::live::viewer::Viewer;
    let mut v = Viewer::connect(&addr).await?;
    let ch = v.advertised(1).await?;
    let scene_id = 1;
    let subs: Vec<(u32, &serde_json::Value)> =
        ch.values().zip(scene_id..).map(|(c, i)| (i, c)).collect();
    let scene_sub = subs
        .iter()
        .find(|(_, c)| c["topic"] == "/match/1/scene")
        .map(|(i, _)| *i);
    v.subscribe(&subs).await?;
    let mut w = Watched::default();
    tokio::pin!(stop);
    loop {
        tokio::select! {
            m = v.next_raw() => match m {
                Some((sub, b)) => {
                    w.messages += 1;
                    w.bytes += b.len() as u64;
                    w.scenes += u64::from(Some(sub) == scene_sub);
                }
                None => break,
            },
            _ = &mut stop => break,
        }
    }
    v.close().await;
    Ok(w)
}

/// Plays `cfg.matches` matches with 8 robot clients each on a fresh server;
/// returns (wall time, ticks played, client errors, missed robot-ticks).
/// With `live`, the server streams its matches there (`--live`) and a
/// viewer watches match 1 from before the clients join.
async fn bench_round(
    cfg: ServerConfig,
    hooks: Hooks,
) -> anyhow::Result<(std::time::Duration, u64, usize, u64)> {
    let (el, ticks, errors, misses, _) = bench_round_watched(cfg, hooks, None).await?;
    Ok((el, ticks, errors, misses))
}

async fn bench_round_watched(
    mut cfg: ServerConfig,
    mut hooks: Hooks,
    live: Option<Arc<naosoccer::live::LiveServer>>,
) -> anyhow::Result<(std::time::Duration, u64, usize, u64, Watched)> {
    use naosoccer_client::robot::{run_team, TeamRun};
    use naosoccer_policy::PolicyKind;
    use naosoccer_proto::msg::{MatchId, Player};
    use naosoccer_proto::Team;
    let tokens = cfg.resolve_tokens();
    cfg.max_connections = 8 * cfg.matches as usize + 16;
    cfg.max_matches = cfg.matches as usize;
    let listener = TcpListener::bind("127.0.0.1:0").await?;
    let addr = listener.local_addr()?.to_string();
    let (stop_tx, stop_rx) = tokio::sync::oneshot::channel::<()>();
    let matches = cfg.matches;
    if let Some(live) = &live {
        hooks.observer = Some(Arc::new(with_live(hooks.observer.take(), live.clone())));
    }
    let server = tokio::spawn(naosoccer_server::run_with(
        listener,
        cfg,
        hooks,
        async move {
            let _ = stop_rx.await;
        },
    ));
    let (viewer_stop, viewer) = match &live {
        Some(live) => {
            let (tx, rx) = tokio::sync::oneshot::channel();
            let task = tokio::spawn(bench_viewer(live.addr().to_string(), rx));
            let l = live.clone();
            let subscribed = tokio::task::spawn_blocking(move || {
                l.wait_for_viewer(std::time::Duration::from_secs(30))
            })
            .await?;
            anyhow::ensure!(subscribed, "the bench viewer did not subscribe within 30 s");
            (Some(tx), Some(task))
        }
        None => (None, None),
    };
    let start = std::time::Instant::now();
    let mut clients = Vec::new();
    for id in 1..=matches {
        for team in Team::BOTH {
            let run = TeamRun {
                server: addr.clone(),
                team,
                token: tokens.team(team).to_owned(),
                match_id: Some(MatchId(u64::from(id))),
                players: Player::all().collect(),
                policy: PolicyKind::Scripted.into(),
                team_connection: false,
            };
            clients.push(tokio::spawn(async move { run_team(&run).await }));
        }
    }
    let (mut errors, mut ticks, mut misses) = (0, 0, 0);
    for (i, c) in clients.into_iter().enumerate() {
        match c.await {
            Ok(Ok(results)) => {
                if let Some(r) = results.first() {
                    let team = if i % 2 == 0 {
                        &r.end.misses.blue
                    } else {
                        &r.end.misses.red
                    };
                    misses += team.iter().sum::<u64>();
                    if i % 2 == 0 {
                        ticks += r.end.tick.get();
                    }
                }
            }
            Ok(Err(e)) => {
                errors += 1;
                tracing::error!(error = %e, "bench client failed");
            }
            Err(e) => {
                errors += 1;
                tracing::error!(error = %e, "bench client panicked");
            }
        }
    }
    let elapsed = start.elapsed();
    let _ = stop_tx.send(());
    server.await??;
    if let Some(tx) = viewer_stop {
        let _ = tx.send(());
    }
    let watched = match viewer {
        Some(task) => task.await??,
        None => Watched::default(),
    };
    Ok((elapsed, ticks, errors, misses, watched))
}

pub fn bench(args: BenchServerArgs) -> anyhow::Result<()> {
    init_logging();
    // Before the bench's runtime: the SDK runs its own (and is stopped
    // outside this one, when the last reference, this one, goes).
    // One live server per watched round (each counts its own viewer).
    let mut lives = Vec::new();
    if args.viewer && args.parts.iter().any(|p| p == "single") {
        for _ in 0..args.viewer_rounds {
            lives.push(Arc::new(naosoccer::live::LiveServer::start("127.0.0.1:0")?));
        }
    }
    let rt = tokio::runtime::Builder::new_multi_thread()
        .enable_all()
        .build()?;
    let lives_ref = lives.clone();
    let res = rt.block_on(async move {
        let lives = lives_ref;
        let mut base = ServerConfig { mode: Mode::Lockstep, ..ServerConfig::default() };
        base.match_cfg.minutes = args.minutes;
        // Every bench client connects from 127.0.0.1: lift the per-address
        // and total connection limits that protect a real server.
        base.max_connections = 4096;
        base.limits.max_connections_per_addr = 4096;

        let run = |part: &str| args.parts.iter().any(|p| p == part);
        if run("single") {
        // The floor: the same match in process (physics, referee, policies).
        let t = std::time::Instant::now();
        let in_proc_ticks = in_process_ticks(&base.match_cfg, base.seed)?;
        let in_proc = t.elapsed();
        println!(
            "in process, no sockets:        {in_proc_ticks} ticks in {:.2} s = {:.0} ticks/s",
            in_proc.as_secs_f64(),
            in_proc_ticks as f64 / in_proc.as_secs_f64()
        );

        let (el, ticks, errors, misses) = bench_round(base.clone(), Hooks::default()).await?;
        let unwatched = ticks as f64 / el.as_secs_f64();
        println!(
            "1 lockstep match, 8 robot clients: {ticks} ticks in {:.2} s = {unwatched:.0} ticks/s (errors {errors}, missed robot-ticks {misses})",
            el.as_secs_f64(),
        );
        if !lives.is_empty() {
            // Unwatched and watched rounds alternate, so a machine whose
            // load drifts weighs on both alike; medians compared.
            let (mut plain, mut watched) = (vec![unwatched], Vec::new());
            for (i, live) in lives.iter().enumerate() {
                if i > 0 {
                    let (el, ticks, errors, misses) = bench_round(base.clone(), Hooks::default()).await?;
                    plain.push(ticks as f64 / el.as_secs_f64());
                    println!(
                        "1 lockstep match, 8 robot clients: {ticks} ticks in {:.2} s = {:.0} ticks/s (errors {errors}, missed robot-ticks {misses})",
                        el.as_secs_f64(),
                        plain[i],
                    );
                }
                let (el, ticks, errors, misses, w) =
                    bench_round_watched(base.clone(), Hooks::default(), Some(live.clone())).await?;
                watched.push(ticks as f64 / el.as_secs_f64());
                println!(
                    "the same match, --live with 1 viewer subscribed to every channel: {ticks} ticks in {:.2} s = {:.0} ticks/s (errors {errors}, missed robot-ticks {misses}); the viewer got {} messages, {} scenes, {:.0} kB ({:.0} kB/s)",
                    el.as_secs_f64(),
                    watched[i],
                    w.messages,
                    w.scenes,
                    w.bytes as f64 / 1e3,
                    w.bytes as f64 / 1e3 / el.as_secs_f64(),
                );
            }
            let median = |v: &mut Vec<f64>| {
                v.sort_by(f64::total_cmp);
                v[v.len() / 2]
            };
            let (p, w) = (median(&mut plain), median(&mut watched));
            println!(
                "a viewer slows the lockstep match by {:.1}% (medians of {} rounds each: {p:.0} unwatched, {w:.0} watched ticks/s; target <= 10%)",
                (1.0 - w / p) * 100.0,
                lives.len(),
            );
        }
        }

        if run("concurrent") {
        let mut many = base.clone();
        many.matches = args.concurrent;
        many.match_cfg.minutes = args.concurrent_minutes;
        let (el, ticks, errors, misses) = bench_round(many, Hooks::default()).await?;
        println!(
            "{} lockstep matches at once, {} robot clients: {ticks} ticks in {:.2} s = {:.0} ticks/s in total (errors {errors}, missed robot-ticks {misses})",
            args.concurrent,
            8 * args.concurrent,
            el.as_secs_f64(),
            ticks as f64 / el.as_secs_f64()
        );
        }

        if run("realtime") {
        let mut rt_cfg = base.clone();
        rt_cfg.mode = Mode::Realtime;
        rt_cfg.matches = args.realtime;
        rt_cfg.match_cfg.minutes = args.realtime_seconds / 60.0;
        let lat = Arc::new(Latencies(std::sync::Mutex::new(Vec::new())));
        let hooks = Hooks {
            observer: Some(Arc::new({
                let lat = lat.clone();
                move |_: &naosoccer_proto::msg::MatchInfo| Some(Box::new(LatencyObserver(lat.clone())) as Box<dyn MatchObserver>)
            })),
            ..Hooks::default()
        };
        let (el, ticks, errors, misses) = bench_round(rt_cfg.clone(), hooks).await?;
        let mut l = std::mem::take(&mut *lat.0.lock().expect("bench lock"));
        l.sort_unstable();
        let pct = |q: f64| l.get(((l.len().max(1) - 1) as f64 * q).round() as usize).copied().unwrap_or_default();
        println!(
            "{} realtime matches at {} Hz: {ticks} ticks in {:.2} s; tick lateness p50 {:.3} ms, p99 {:.3} ms, max {:.3} ms (errors {errors}, missed robot-ticks {misses})",
            args.realtime,
            rt_cfg.match_cfg.control_hz,
            el.as_secs_f64(),
            pct(0.5).as_secs_f64() * 1e3,
            pct(0.99).as_secs_f64() * 1e3,
            l.last().copied().unwrap_or_default().as_secs_f64() * 1e3,
        );
        }
        Ok(())
    });
    drop(rt);
    drop(lives);
    res
}

fn in_process_ticks(cfg: &naosoccer_referee::MatchConfig, seed: u64) -> anyhow::Result<u64> {
    use naosoccer_policy::PolicyKind;
    use naosoccer_proto::{Action, RobotId, ROBOTS};
    let mut game = naosoccer_referee::Match::new(cfg, seed)?;
    let mut policies: Vec<_> = RobotId::all()
        .map(|r| PolicyKind::Scripted.build(seed, r))
        .collect();
    let mut actions = [Action::Stay; ROBOTS];
    let mut obs = game.observe(naosoccer_proto::Team::Blue, 0);
    while !game.is_finished() {
        for r in RobotId::all() {
            game.observe_into(r.team(), r.player(), &mut obs);
            actions[r.index()] = policies[r.index()].act(&obs);
        }
        game.step(&actions);
    }
    Ok(game.tick().get())
}
