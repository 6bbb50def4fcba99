//! `naosoccer bench soak`: many lockstep matches at once for a while, with
//! well-behaved, reconnecting and misbehaving clients mixed in; prints what
//! the server did and how its memory went (issue 6).
use anyhow::Context;
use clap::Args;
use naosoccer_client::{Client, ClientError, Push};
use naosoccer_policy::PolicyKind;
use naosoccer_proto::msg::{
    ActionMsg, ClientMsg, CreateMatch, EndReason, ErrorCode, MatchId, Mode, Player, PlayerAction,
};
use naosoccer_proto::{Action, RobotId, Team};
use naosoccer_server::ServerConfig;
use std::collections::BTreeMap;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};
use tokio::io::{AsyncReadExt, AsyncWriteExt};
use tokio::net::TcpListener;
use tokio::sync::watch;

/// `naosoccer bench soak`.
#[derive(Args, Debug)]
#[command(after_help = "\
Runs an in-process server on 127.0.0.1 and --matches match slots for --minutes of \
wall-clock time; each slot plays one lockstep match after another until the time is \
up (the last one is finished). Blue is always a well-behaved team client. Red is, by \
slot: a team client; a team client; four robot clients that drop their connection \
mid-match and reconnect to take their robot back; or a misbehaving client (invalid \
frames, acting for the other team, future ticks, floods, missed ticks, and every \
other time it stops reading until the server drops it), joined by a peer that never \
says hello and one that sends half a frame. Prints matches completed, ticks, errors \
by code, peak RSS (VmHWM) and RSS over time.")]
pub struct SoakArgs {
    /// Match slots played at once.
    #[arg(long, default_value_t = 64)]
    pub matches: u32,
    /// Wall-clock minutes to keep starting matches.
    #[arg(long, default_value_t = 5.0)]
    pub minutes: f64,
    /// Length of each match in minutes of game time.
    #[arg(long, default_value_t = 0.5)]
    pub match_minutes: f32,
    /// Lockstep deadline per tick in milliseconds.
    #[arg(long, default_value_t = 100)]
    pub deadline_ms: u64,
    /// Seed of the first match (match i gets seed + i - 1).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// RSS samples printed over the run.
    #[arg(long, default_value_t = 10)]
    pub samples: u32,
    /// Record every match here (MCAP) and check afterwards that each
    /// recording is complete.
    #[arg(long, value_name = "DIR")]
    pub record_dir: Option<std::path::PathBuf>,
}

#[derive(Default)]
struct Tally {
    finished: u64,
    other_ends: BTreeMap<String, u64>,
    ticks: u64,
    errors: BTreeMap<String, u64>,
    client_failures: BTreeMap<String, u64>,
    kicked: u64,
}

type Shared = Arc<Mutex<Tally>>;

fn count_error(t: &Shared, code: ErrorCode) {
    *t.lock()
        .expect("tally lock")
        .errors
        .entry(code.to_string())
        .or_default() += 1;
}

fn count_failure(t: &Shared, what: &str) {
    *t.lock()
        .expect("tally lock")
        .client_failures
        .entry(what.to_owned())
        .or_default() += 1;
}

/// VmRSS and VmHWM of this process in KiB.
fn rss_kib() -> (u64, u64) {
    let status = std::fs::read_to_string("/proc/self/status").unwrap_or_default();
    let field = |name: &str| {
        status
            .lines()
            .find(|l| l.starts_with(name))
            .and_then(|l| l.split_whitespace().nth(1))
            .and_then(|v| v.parse().ok())
            .unwrap_or(0)
    };
    (field("VmRSS:"), field("VmHWM:"))
}

struct Ctx {
    addr: String,
    blue: String,
    red: String,
    admin: String,
    tally: Shared,
}

pub fn soak(args: SoakArgs) -> anyhow::Result<()> {
    super::server::init_logging();
    anyhow::ensure!(args.matches > 0, "--matches must be at least 1");
    anyhow::ensure!(
        args.minutes > 0.0 && args.minutes.is_finite(),
        "--minutes must be positive"
    );
    let rt = tokio::runtime::Builder::new_multi_thread()
        .enable_all()
        .build()?;
    rt.block_on(run(args))
}

async fn run(args: SoakArgs) -> anyhow::Result<()> {
    let mut cfg = ServerConfig {
        mode: Mode::Lockstep,
        matches: 0,
        seed: args.seed,
        deadline_ms: args.deadline_ms,
        max_matches: args.matches as usize,
        max_connections: 16 * args.matches as usize + 64,
        ..ServerConfig::default()
    };
    cfg.match_cfg.minutes = args.match_minutes;
    cfg.record_dir = args.record_dir.clone();
    cfg.limits.max_connections_per_addr = cfg.max_connections;
    cfg.limits.hello_timeout_ms = 2_000;
    cfg.limits.frame_timeout_ms = 2_000;
    cfg.limits.write_timeout_ms = 2_000;
    cfg.limits.messages_per_second = 2_000;
    cfg.limits.message_burst = 200;
    cfg.validate()?;
    let tokens = cfg.resolve_tokens();
    let listener = TcpListener::bind("127.0.0.1:0").await?;
    let addr = listener.local_addr()?.to_string();
    let (stop_tx, stop_rx) = tokio::sync::oneshot::channel::<()>();
    let server = tokio::spawn(naosoccer_server::run(listener, cfg, async move {
        let _ = stop_rx.await;
    }));
    let ctx = Arc::new(Ctx {
        addr,
        blue: tokens.blue.clone(),
        red: tokens.red.clone(),
        admin: tokens.admin.clone(),
        tally: Shared::default(),
    });

    let started = Instant::now();
    let until = started + Duration::from_secs_f64(args.minutes * 60.0);
    let (rss0, _) = rss_kib();
    let sampler = {
        let every = Duration::from_secs_f64(args.minutes * 60.0 / f64::from(args.samples.max(1)));
        let tally = ctx.tally.clone();
        tokio::spawn(async move {
            let mut samples = Vec::new();
            let mut tick = tokio::time::interval_at(tokio::time::Instant::now() + every, every);
            loop {
                tick.tick().await;
                let (rss, _) = rss_kib();
                let done = tally.lock().expect("tally lock").finished;
                samples.push((started.elapsed(), rss, done));
                if Instant::now() >= until {
                    return samples;
                }
            }
        })
    };
    let mut slots = Vec::new();
    for slot in 0..args.matches {
        let ctx = ctx.clone();
        slots.push(tokio::spawn(async move {
            while Instant::now() < until {
                if let Err(e) = play_one(&ctx, slot).await {
                    tracing::warn!(slot, error = %e, "soak slot failed");
                    count_failure(&ctx.tally, "slot");
                }
            }
        }));
    }
    for s in slots {
        s.await.context("a soak slot panicked")?;
    }
    let elapsed = started.elapsed();
    let samples = sampler.await?;
    let _ = stop_tx.send(());
    let server_result = server.await;
    let (rss_end, hwm) = rss_kib();

    let t = ctx.tally.lock().expect("tally lock");
    println!(
        "soak: {} match slots for {:.1} min ({:.2} game-minute matches, lockstep, deadline {} ms)",
        args.matches,
        elapsed.as_secs_f64() / 60.0,
        args.match_minutes,
        args.deadline_ms
    );
    println!(
        "matches completed: {} (other ends: {:?}); ticks: {} ({:.0}/s)",
        t.finished,
        t.other_ends,
        t.ticks,
        t.ticks as f64 / elapsed.as_secs_f64()
    );
    println!("errors received by clients, by code: {:?}", t.errors);
    println!(
        "misbehaving clients dropped for not reading: {}; client failures: {:?}",
        t.kicked, t.client_failures
    );
    println!(
        "server: {}",
        match &server_result {
            Ok(Ok(())) => "ran to the end and shut down cleanly".to_owned(),
            Ok(Err(e)) => format!("FAILED: {e}"),
            Err(e) => format!("CRASHED: {e}"),
        }
    );
    println!(
        "RSS: start {:.1} MiB, end {:.1} MiB, peak (VmHWM) {:.1} MiB",
        rss0 as f64 / 1024.0,
        rss_end as f64 / 1024.0,
        hwm as f64 / 1024.0
    );
    println!("RSS over time:");
    for (at, rss, done) in samples {
        println!(
            "  {:>7.1} s  {:>7.1} MiB  {done} matches completed",
            at.as_secs_f64(),
            rss as f64 / 1024.0
        );
    }
    if let Some(dir) = &args.record_dir {
        let (mut complete, mut incomplete) = (0u64, Vec::new());
        for entry in std::fs::read_dir(dir).with_context(|| format!("reading {}", dir.display()))? {
            let path = entry?.path();
            if path.extension().is_some_and(|e| e == "mcap") {
                match naosoccer_record::Recording::read_file(&path) {
                    Ok(r) if r.is_complete() => complete += 1,
                    _ => incomplete.push(path.display().to_string()),
                }
            }
        }
        println!(
            "recordings: {complete} complete, {} incomplete or unreadable {:?}",
            incomplete.len(),
            incomplete
        );
    }
    match server_result {
        Ok(r) => r.map_err(Into::into),
        Err(e) => Err(anyhow::anyhow!("the server task panicked: {e}")),
    }
}

/// One match in a slot: create it, play both sides, tally the outcome.
async fn play_one(ctx: &Arc<Ctx>, slot: u32) -> anyhow::Result<()> {
    let mut admin = Client::connect(ctx.addr.as_str(), "soak-admin").await?;
    let info = admin
        .create_match(CreateMatch {
            token: ctx.admin.clone(),
            start_players: Some(8),
            ..Default::default()
        })
        .await?;
    drop(admin);
    let id = info.match_id;
    let (over_tx, over) = watch::channel(false);
    let red: tokio::task::JoinHandle<()> = match slot % 4 {
        0 | 1 => {
            let ctx = ctx.clone();
            tokio::spawn(async move { team(&ctx, id, Team::Red).await })
        }
        2 => {
            let ctx = ctx.clone();
            tokio::spawn(async move { reconnecting(&ctx, id).await })
        }
        _ => {
            let ctx = ctx.clone();
            let hold = (id.0 / 4) % 2 == 1;
            tokio::spawn(async move { misbehaving(&ctx, id, hold, over).await })
        }
    };
    if slot % 4 == 3 {
        for half in [false, true] {
            let ctx = ctx.clone();
            tokio::spawn(async move { hostile(&ctx, half).await });
        }
    }
    team(ctx, id, Team::Blue).await;
    let _ = over_tx.send(true);
    red.await?;
    Ok(())
}

fn token(ctx: &Ctx, team: Team) -> String {
    match team {
        Team::Blue => ctx.blue.clone(),
        Team::Red => ctx.red.clone(),
    }
}

fn note_end(ctx: &Ctx, end: &naosoccer_proto::msg::MatchEnd, count_ticks: bool) {
    let mut t = ctx.tally.lock().expect("tally lock");
    if end.reason == EndReason::Finished {
        if count_ticks {
            t.finished += 1;
            t.ticks += end.tick.get();
        }
    } else {
        *t.other_ends.entry(format!("{:?}", end.reason)).or_default() += 1;
    }
}

fn note_client_error(ctx: &Ctx, e: &ClientError) {
    match e {
        ClientError::Server(e) => count_error(&ctx.tally, e.code),
        other => {
            tracing::warn!(error = %other, "soak client failed");
            count_failure(&ctx.tally, "client");
        }
    }
}

/// A well-behaved team client with the scripted policy; blue's end is the
/// one counted.
async fn team(ctx: &Ctx, id: MatchId, team: Team) {
    let r = async {
        let mut c = Client::connect(ctx.addr.as_str(), "soak-team").await?;
        let players: Vec<Player> = Player::all().collect();
        let joined = c.join(Some(id), team, &token(ctx, team), &players).await?;
        let mut policies: Vec<_> = players
            .iter()
            .map(|p| {
                let robot = RobotId::new(team, p.index()).expect("player index");
                PolicyKind::Scripted.build(joined.seed, robot)
            })
            .collect();
        c.play(&joined, &mut policies).await.map(|p| p.end)
    }
    .await;
    match r {
        Ok(end) => note_end(ctx, &end, team == Team::Blue),
        Err(e) => note_client_error(ctx, &e),
    }
}

/// Four robot clients, each dropping its connection after some ticks and
/// coming back on a new one to take its robot back.
async fn reconnecting(ctx: &Arc<Ctx>, id: MatchId) {
    let mut robots = Vec::new();
    for p in Player::all() {
        let ctx = ctx.clone();
        robots.push(tokio::spawn(async move {
            let r: Result<(), ClientError> = async {
                let stay = [PlayerAction {
                    player: p,
                    action: Action::Forward,
                }];
                let mut c = Client::connect(ctx.addr.as_str(), "soak-robot").await?;
                c.join(Some(id), Team::Red, &ctx.red, &[p]).await?;
                let leave_after = 20 + 15 * p.index() as u64;
                let mut played = 0;
                loop {
                    match c.next_push().await? {
                        Push::Observation(o) => {
                            c.send_actions(o.tick, &stay).await?;
                            played += 1;
                            if played == leave_after {
                                break;
                            }
                        }
                        Push::MatchEnd(_) => return Ok(()),
                        Push::Error(e) => count_error(&ctx.tally, e.code),
                    }
                }
                drop(c);
                // Back on a new connection; the old one's slot frees once
                // the server has seen it close.
                let mut c = Client::connect(ctx.addr.as_str(), "soak-robot-again").await?;
                for attempt in 0.. {
                    match c.join(Some(id), Team::Red, &ctx.red, &[p]).await {
                        Ok(_) => break,
                        Err(ClientError::Server(e))
                            if e.code == ErrorCode::FailedPrecondition
                                && e.message.contains("already controlled")
                                && attempt < 1000 =>
                        {
                            tokio::time::sleep(Duration::from_millis(1)).await;
                        }
                        Err(e) => return Err(e),
                    }
                }
                loop {
                    match c.next_push().await? {
                        Push::Observation(o) => c.send_actions(o.tick, &stay).await?,
                        Push::MatchEnd(end) => {
                            note_end(&ctx, &end, false);
                            return Ok(());
                        }
                        Push::Error(e) => count_error(&ctx.tally, e.code),
                    }
                }
            }
            .await;
            if let Err(e) = r {
                note_client_error(&ctx, &e);
            }
        }));
    }
    for r in robots {
        let _ = r.await;
    }
}

/// Red as a buggy or hostile team client: garbage frames, actions for blue,
/// future ticks, floods, silence; with `hold`, it stops reading after a
/// while (until the match is over) so the server must drop it.
async fn misbehaving(ctx: &Ctx, id: MatchId, hold: bool, mut over: watch::Receiver<bool>) {
    let r: Result<(), ClientError> = async {
        // A small receive buffer, so a client that stops reading fills its
        // queue on the server soon rather than the kernel's buffers.
        let sock = tokio::net::TcpSocket::new_v4().map_err(ClientError::Connect)?;
        sock.set_recv_buffer_size(4096)
            .map_err(ClientError::Connect)?;
        let addr: std::net::SocketAddr = ctx
            .addr
            .parse()
            .map_err(|e| ClientError::Connect(std::io::Error::other(e)))?;
        let stream = sock.connect(addr).await.map_err(ClientError::Connect)?;
        let mut c = Client::handshake(
            stream,
            &naosoccer_proto::msg::Hello::new("soak-misbehaving"),
        )
        .await?;
        let players: Vec<Player> = Player::all().collect();
        c.join(Some(id), Team::Red, &ctx.red, &players).await?;
        let actions: Vec<PlayerAction> = players
            .iter()
            .map(|&player| PlayerAction {
                player,
                action: Action::TurnLeft,
            })
            .collect();
        let mut n = 0u64;
        loop {
            let o = match c.next_push().await {
                Ok(Push::Observation(o)) => o,
                Ok(Push::MatchEnd(_)) => return Ok(()),
                Ok(Push::Error(e)) => {
                    count_error(&ctx.tally, e.code);
                    continue;
                }
                Err(ClientError::Server(e)) => {
                    if e.code == ErrorCode::ResourceExhausted {
                        ctx.tally.lock().expect("tally lock").kicked += 1;
                    }
                    count_error(&ctx.tally, e.code);
                    return Ok(());
                }
                Err(e) => return Err(e),
            };
            n += 1;
            match n % 10 {
                0 => {
                    c.send_raw(&[0, 0, 0, 5, b'{', b'b', b'a', b'd', b'}'])
                        .await?
                }
                1 => {
                    c.send(&ClientMsg::Action(ActionMsg {
                        tick: o.tick,
                        team: Some(Team::Blue),
                        actions: actions.clone(),
                    }))
                    .await?
                }
                2 => c.send_actions(o.tick + 5, &actions).await?,
                3 => {} // a miss
                4 if n % 50 == 4 => {
                    // A flood past the burst: some refused, none fatal.
                    let mut flood = Vec::new();
                    for _ in 0..300 {
                        flood.extend_from_slice(&[0, 0, 0, 2, b'{', b'}']);
                    }
                    c.send_raw(&flood).await?;
                    c.send_actions(o.tick, &actions).await?;
                }
                _ => c.send_actions(o.tick, &actions).await?,
            }
            if hold && n == 100 {
                // Stop reading, keep the connection, until the match is
                // over; then see how the server parted with it.
                let _ = over.wait_for(|o| *o).await;
                loop {
                    match c.next_push().await {
                        Ok(Push::MatchEnd(_)) => return Ok(()),
                        Ok(_) => {}
                        Err(ClientError::Server(e)) => {
                            if e.code == ErrorCode::ResourceExhausted {
                                ctx.tally.lock().expect("tally lock").kicked += 1;
                            }
                            count_error(&ctx.tally, e.code);
                            return Ok(());
                        }
                        // Closed by the write deadline before the kick
                        // notice could be written.
                        Err(_) => {
                            ctx.tally.lock().expect("tally lock").kicked += 1;
                            return Ok(());
                        }
                    }
                }
            }
        }
    }
    .await;
    if let Err(e) = r {
        note_client_error(ctx, &e);
    }
}

/// A peer that never says hello, or sends half a frame: the server's
/// deadlines close it.
async fn hostile(ctx: &Ctx, half: bool) {
    let Ok(mut s) = tokio::net::TcpStream::connect(ctx.addr.as_str()).await else {
        count_failure(&ctx.tally, "hostile connect");
        return;
    };
    if half {
        let _ = s.write_all(&[0, 0, 1, 0, b'{', b'"']).await;
    }
    let mut sink = Vec::new();
    match tokio::time::timeout(Duration::from_secs(30), s.read_to_end(&mut sink)).await {
        Ok(_) => {
            if sink.len() > 4 {
                if let Ok(naosoccer_proto::msg::ServerMsg::Error(e)) =
                    serde_json::from_slice::<naosoccer_proto::msg::ServerMsg>(&sink[4..])
                {
                    count_error(&ctx.tally, e.code);
                }
            }
        }
        Err(_) => count_failure(&ctx.tally, "hostile peer never closed"),
    }
}
