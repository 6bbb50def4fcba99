//! `naosoccer server`: the match server (`bench server` is in bench_server.rs).
use anyhow::Context;
use clap::Args;
use naosoccer_proto::msg::{Fill, Mode};
use naosoccer_server::{FillTeam, Hooks, MatchObserver, ServerConfig, TickRecord};
use std::path::PathBuf;
use std::sync::Arc;
use tokio::net::TcpListener;

#[derive(Args, Debug)]
#[command(after_help = "\
The server listens on 127.0.0.1 (loopback only) unless --bind says otherwise. \
At start it creates --matches matches (ids 1..N, seeds --seed, --seed+1, ...) and \
prints the team and admin tokens (random unless set in the config file or here). \
A match starts once --start-players robots have joined (8: every slot is a \
client); slots nobody joined are played by --fill. Ctrl-C or SIGTERM stops \
every match; clients get a final match_end. Protocol: docs/PROTOCOL.md.")]
pub struct ServerArgs {
    /// Server configuration TOML: address, port, mode, fill, tokens,
    /// limits (every field optional; docs/PROTOCOL.md section 8).
    #[arg(long, value_name = "FILE")]
    pub server_config: Option<PathBuf>,
    /// Address to listen on [default: 127.0.0.1, loopback only].
    #[arg(long, value_name = "ADDR")]
    pub bind: Option<String>,
    /// TCP port [default: 7878; 0 picks a free one].
    #[arg(long)]
    pub port: Option<u16>,
    /// lockstep (a tick waits for every client, up to the deadline) or realtime (fixed rate).
    #[arg(long, value_name = "lockstep|realtime")]
    pub mode: Option<Mode>,
    /// Matches created at start [default: 1].
    #[arg(long)]
    pub matches: Option<u32>,
    /// Seed of match 1 (match i gets seed+i-1) [default: 1].
    #[arg(long)]
    pub seed: Option<u64>,
    /// Match length in minutes, overriding the match configuration [default: 10].
    #[arg(long)]
    pub minutes: Option<f32>,
    /// Match configuration TOML, as `--config` of `match` and `eval`
    /// [default: the built-in assets/match.toml].
    #[arg(long = "config", visible_alias = "match-config", value_name = "FILE")]
    pub match_config: Option<PathBuf>,
    /// Who plays slots no client joined: scripted, scripted:1 to scripted:5
    /// (the ladder of built-in teams, weakest first), idle, or, in the
    /// empty slots of every match whatever a create_match asks, a scripted
    /// variant (scripted:KEY=VAL,..., scripted:N,KEY=VAL,...,
    /// scripted:FILE.toml) or a trained team (ppo:DIR, ppo-greedy:DIR,
    /// dqn:DIR, dqn-epsilon:DIR).
    #[arg(
        long,
        value_name = "scripted[:N]|idle|scripted:KEY=VAL|ppo:DIR|dqn:DIR"
    )]
    pub fill: Option<String>,
    /// Robots that must join before a match starts, 0..=8 [default: 8].
    #[arg(long)]
    pub start_players: Option<u8>,
    /// Lockstep deadline per tick in milliseconds [default: 1000].
    #[arg(long)]
    pub deadline_ms: Option<u64>,
    /// Blue's team token [default: from --server-config, else random and printed].
    #[arg(long, value_name = "TOKEN")]
    pub blue_token: Option<String>,
    /// Red's team token [default: from --server-config, else random and printed].
    #[arg(long, value_name = "TOKEN")]
    pub red_token: Option<String>,
    /// The admin token (create_match, end_match, set_state) [default: from --server-config, else random and printed].
    #[arg(long, value_name = "TOKEN")]
    pub admin_token: Option<String>,
    /// Exit once the matches created at start have all ended.
    #[arg(long)]
    pub exit_when_done: bool,
    /// Record every match to this directory, one MCAP file per match
    /// (docs/RECORDINGS.md) [default: from --server-config, else ./recordings].
    #[arg(long, value_name = "DIR", conflicts_with = "no_record")]
    pub record_dir: Option<PathBuf>,
    /// Do not record matches.
    #[arg(long)]
    pub no_record: bool,
    /// Stream every match live to Foxglove (Foxglove
    /// WebSocket on ADDR, default 127.0.0.1:8765; topics /match/ID/..., one
    /// set per match id; docs/RECORDINGS.md). Viewers never slow a match down.
    #[arg(long, value_name = "ADDR", num_args = 0..=1,
          default_missing_value = naosoccer::live::DEFAULT_ADDR)]
    pub live: Option<String>,
    /// Per-connection limits (boxed: they would make every command large).
    #[command(flatten)]
    pub limits: Box<LimitArgs>,
}

/// `naosoccer server` limit options; absent ones keep the config file's value.
#[derive(Args, Debug)]
#[command(next_help_heading = "Limits (docs/PROTOCOL.md section 9)")]
pub struct LimitArgs {
    /// Connections served at once; more get `resource_exhausted` [default: 256].
    #[arg(long)]
    pub max_connections: Option<usize>,
    /// Connections at once from one IP address [default: 64].
    #[arg(long)]
    pub max_connections_per_addr: Option<usize>,
    /// Unfinished matches at once [default: 64].
    #[arg(long)]
    pub max_matches: Option<usize>,
    /// Joins over one connection's life [default: 256].
    #[arg(long)]
    pub max_joins_per_connection: Option<u32>,
    /// Sustained messages a second per connection; more are refused [default: 20000].
    #[arg(long)]
    pub messages_per_second: Option<u32>,
    /// Messages a connection may send at once above that rate [default: 20000].
    #[arg(long)]
    pub message_burst: Option<u32>,
    /// A connection without `hello` this long is closed [default: 10000].
    #[arg(long)]
    pub hello_timeout_ms: Option<u64>,
    /// A connection silent this long is closed (lobby clients ping) [default: 600000].
    #[arg(long)]
    pub idle_timeout_ms: Option<u64>,
}

/// `--config` is the match configuration for `server` as for every other
/// subcommand (before, it was the server's own configuration): a server
/// configuration given there is named as such, with the option it belongs to.
fn refuse_server_config_as_match_config(path: &std::path::Path) -> anyhow::Result<()> {
    let Ok(text) = std::fs::read_to_string(path) else {
        return Ok(()); // the match configuration's loader reports it
    };
    let Ok(table) = text.parse::<toml::Table>() else {
        return Ok(());
    };
    const SERVER_KEYS: [&str; 9] = [
        "bind",
        "port",
        "mode",
        "fill",
        "matches",
        "tokens",
        "limits",
        "record_dir",
        "start_players",
    ];
    let found: Vec<&str> = SERVER_KEYS
        .into_iter()
        .filter(|k| table.contains_key(*k))
        .collect();
    if found.is_empty() {
        return Ok(());
    }
    anyhow::bail!(
        "--config {}: this is a server configuration ({}), not a match configuration: \
         pass it with --server-config",
        path.display(),
        found.join(", ")
    )
}

fn config_from(args: &ServerArgs) -> anyhow::Result<ServerConfig> {
    let mut cfg = match &args.server_config {
        Some(path) => {
            ServerConfig::from_file(path).with_context(|| format!("loading {}", path.display()))?
        }
        None => ServerConfig::default(),
    };
    if let Some(path) = &args.match_config {
        refuse_server_config_as_match_config(path)?;
    }
    macro_rules! set {
        ($($field:ident),*) => { $( if let Some(v) = &args.$field { cfg.$field = v.clone(); } )* };
    }
    set!(bind, port, mode, matches, seed, start_players, deadline_ms);
    if let Some(f) = args
        .fill
        .as_deref()
        .filter(|f| !naosoccer_policy::is_learned_spec(f) && !is_variant_fill(f))
    {
        cfg.fill = f
            .parse::<Fill>()
            .map_err(|e| anyhow::anyhow!("--fill: {e}, or a trained team such as ppo:DIR"))?;
    }
    if args.match_config.is_some() {
        cfg.match_config = args.match_config.clone();
    }
    if args.minutes.is_some() {
        cfg.minutes = args.minutes;
    }
    if let Some(t) = &args.blue_token {
        cfg.tokens.blue = Some(t.clone());
    }
    if let Some(t) = &args.red_token {
        cfg.tokens.red = Some(t.clone());
    }
    if let Some(t) = &args.admin_token {
        cfg.tokens.admin = Some(t.clone());
    }
    let limits = &args.limits;
    if let Some(v) = limits.max_connections {
        cfg.max_connections = v;
    }
    if let Some(v) = limits.max_matches {
        cfg.max_matches = v;
    }
    macro_rules! limit {
        ($($field:ident),*) => { $( if let Some(v) = limits.$field { cfg.limits.$field = v; } )* };
    }
    limit!(
        max_connections_per_addr,
        max_joins_per_connection,
        messages_per_second,
        message_burst,
        hello_timeout_ms,
        idle_timeout_ms
    );
    if args.no_record {
        cfg.record_dir = None;
    } else if let Some(dir) = &args.record_dir {
        cfg.record_dir = Some(dir.clone());
    } else if cfg.record_dir.is_none() {
        cfg.record_dir = Some(PathBuf::from("recordings"));
    }
    cfg.resolve_match_config()?;
    Ok(cfg)
}

/// A scripted variant that is no `Fill` of the protocol (not a level): it
/// plays the empty slots of every match as a fill team does.
fn is_variant_fill(spec: &str) -> bool {
    spec.starts_with("scripted:") && spec.parse::<Fill>().is_err()
}

pub fn init_logging() {
    use tracing_subscriber::EnvFilter;
    let filter = EnvFilter::try_from_default_env().unwrap_or_else(|_| EnvFilter::new("info"));
    let _ = tracing_subscriber::fmt()
        .with_env_filter(filter)
        .with_ansi(std::io::IsTerminal::is_terminal(&std::io::stderr()))
        .with_writer(std::io::stderr)
        .try_init();
}

pub fn run(args: ServerArgs) -> anyhow::Result<()> {
    init_logging();
    let mut cfg = config_from(&args)?;
    // A trained fill team is loaded once, here, so a bad spec fails at start;
    // every match gets a copy (its draws keyed by that match's seed).
    let learned_fill = match args.fill.as_deref() {
        Some(f) if naosoccer_policy::is_learned_spec(f) => Some((
            f.to_string(),
            naosoccer_policy::LearnedPolicy::load(f)
                .with_context(|| format!("loading --fill {f}"))?,
        )),
        _ => None,
    };
    // A scripted variant, parsed here so that a bad one fails at start. It
    // plays with its own parameters on any pitch (levels, as `Fill`s, take
    // the match's pitch sizes).
    let variant_fill = match args.fill.as_deref() {
        Some(f) if is_variant_fill(f) => Some((
            f.to_string(),
            f.parse::<naosoccer_policy::PolicyKind>()
                .map_err(|e| anyhow::anyhow!("--fill: {e}"))?,
        )),
        _ => None,
    };
    let tokens = cfg.resolve_tokens();
    // Before the server's runtime: the SDK runs its own.
    let live = match &args.live {
        Some(addr) => Some(Arc::new(naosoccer::live::LiveServer::start(addr)?)),
        None => None,
    };
    let rt = tokio::runtime::Builder::new_multi_thread()
        .enable_all()
        .build()?;
    rt.block_on(async move {
        let addr = format!("{}:{}", cfg.bind, cfg.port);
        let listener = TcpListener::bind(&addr)
            .await
            .with_context(|| format!("cannot listen on {addr}"))?;
        let local = listener.local_addr()?;
        {
            // Written with errors ignored: a reader that stops after the
            // address line (`| head -1`, a test) must not kill the server.
            use std::io::Write;
            let mut out = std::io::stdout().lock();
            let _ = writeln!(
                out,
                "naosoccer server on {local} ({} mode, {} match(es))",
                cfg.mode, cfg.matches
            );
            let _ = writeln!(out, "blue token:  {}", tokens.blue);
            let _ = writeln!(out, "red token:   {}", tokens.red);
            let _ = writeln!(out, "admin token: {}", tokens.admin);
            let _ = out.flush();
        }
        let (all_done_tx, all_done) = tokio::sync::watch::channel(false);
        let mut hooks = Hooks::default();
        if let Some((spec, team)) = learned_fill {
            hooks.fill = Some(FillTeam {
                spec,
                make: Arc::new(move |seed, _robot| {
                    let mut p = team.clone();
                    p.set_match_seed(seed);
                    Box::new(p) as Box<dyn naosoccer_policy::Policy>
                }),
            });
        }
        if let Some((spec, kind)) = variant_fill {
            hooks.fill = Some(FillTeam {
                spec,
                make: Arc::new(move |seed, robot| kind.build(seed, robot)),
            });
        }
        if args.exit_when_done {
            hooks.observer = Some(Arc::new(done_counter(cfg.matches, all_done_tx)));
        }
        let live_after = live.clone();
        if let Some(live) = live {
            hooks.observer = Some(Arc::new(with_live(hooks.observer.take(), live)));
        }
        let shutdown = async move {
            let mut all_done = all_done;
            tokio::select! {
                _ = signal() => {}
                _ = all_done.wait_for(|d| *d), if args.exit_when_done => {}
            }
        };
        naosoccer_server::run_with(listener, cfg, hooks, shutdown).await?;
        if let Some(live) = live_after {
            // Viewers still connected get the last ticks queued for them
            // before the process exits (`--exit-when-done`).
            tokio::task::spawn_blocking(move || live.linger(naosoccer::live::LINGER)).await?;
        }
        Ok(())
    })
}

/// `--live`: `inner`'s observers (if any) plus a live stream per match.
pub(crate) fn with_live(
    inner: Option<Arc<naosoccer_server::observer::ObserverFactory>>,
    live: Arc<naosoccer::live::LiveServer>,
) -> impl Fn(&naosoccer_proto::msg::MatchInfo) -> Option<Box<dyn MatchObserver>> + Send + Sync {
    move |info| {
        let mut all: Vec<Box<dyn MatchObserver>> = Vec::new();
        if let Some(o) = inner.as_ref().and_then(|f| f(info)) {
            all.push(o);
        }
        match naosoccer::live::LiveObserver::new(&live, info.match_id.0) {
            Ok(o) => all.push(Box::new(o)),
            Err(e) => tracing::warn!(
                "match {}: no live stream: {}",
                info.match_id.0,
                crate::cmd::error_text(&e)
            ),
        }
        Some(Box::new(naosoccer_server::recording::Fanout(all)))
    }
}

/// An observer factory whose observers count ended matches among the first `n`.
fn done_counter(
    n: u32,
    tx: tokio::sync::watch::Sender<bool>,
) -> impl Fn(&naosoccer_proto::msg::MatchInfo) -> Option<Box<dyn MatchObserver>> + Send + Sync {
    struct Count {
        left: Arc<std::sync::atomic::AtomicU32>,
        tx: tokio::sync::watch::Sender<bool>,
    }
    impl MatchObserver for Count {
        fn on_start(&mut self, _: &naosoccer_proto::msg::MatchInfo, _: &naosoccer_referee::Match) {}
        fn on_tick(&mut self, _: &TickRecord<'_>) {}
        fn on_end(&mut self, _: &naosoccer_proto::msg::MatchEnd, _: &naosoccer_referee::Match) {
            if self.left.fetch_sub(1, std::sync::atomic::Ordering::SeqCst) == 1 {
                let _ = self.tx.send(true);
            }
        }
    }
    let left = Arc::new(std::sync::atomic::AtomicU32::new(n));
    move |info| {
        (info.match_id.0 <= u64::from(n)).then(|| {
            Box::new(Count {
                left: left.clone(),
                tx: tx.clone(),
            }) as Box<_>
        })
    }
}

/// Ctrl-C, or SIGTERM on Unix.
async fn signal() {
    #[cfg(unix)]
    {
        use tokio::signal::unix::{signal, SignalKind};
        match signal(SignalKind::terminate()) {
            Ok(mut term) => tokio::select! {
                _ = tokio::signal::ctrl_c() => {}
                _ = term.recv() => {}
            },
            Err(_) => {
                let _ = tokio::signal::ctrl_c().await;
            }
        }
    }
    #[cfg(not(unix))]
    {
        let _ = tokio::signal::ctrl_c().await;
    }
}
