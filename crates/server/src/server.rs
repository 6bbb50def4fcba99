//! The listener, the match registry and shutdown.

use crate::config::{ServerConfig, Tokens};
use crate::connection;
use crate::match_task::{MatchCmd, MatchParams, MatchTask};
use crate::observer::Hooks;
use naosoccer_proto::frame::encode;
use naosoccer_proto::msg::{
    CreateMatch, ErrorCode, ErrorMsg, MatchId, MatchInfo, MatchState, Player, ServerMsg,
};
use naosoccer_proto::Team;
use naosoccer_referee::Match;
use std::collections::{BTreeMap, HashMap};
use std::future::Future;
use std::net::IpAddr;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Duration;
use tokio::io::AsyncWriteExt;
use tokio::net::{TcpListener, TcpStream};
use tokio::sync::{mpsc, watch, Semaphore};

/// Why the server could not run.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ServerError {
    #[error(transparent)]
    Config(#[from] crate::config::ConfigError),
    #[error("could not create match: {0}")]
    Match(#[from] naosoccer_referee::MatchError),
    #[error("i/o error: {0}")]
    Io(#[from] std::io::Error),
}

/// Finished matches kept for `list_matches`; older ones are forgotten.
const KEEP_FINISHED: usize = 64;
/// Commands queued to one match task.
const MATCH_QUEUE: usize = 256;

struct MatchEntry {
    tx: mpsc::Sender<MatchCmd>,
    info: watch::Receiver<MatchInfo>,
}

/// What every connection shares. Match state is not here: each match task
/// owns its own; this holds only the handles to reach them.
pub(crate) struct Shared {
    pub(crate) config: ServerConfig,
    pub(crate) tokens: Tokens,
    hooks: Hooks,
    matches: Mutex<Registry>,
    shutdown: watch::Receiver<bool>,
    /// Each task holds a clone; `run` waits for all of them to drop.
    done: mpsc::Sender<()>,
    next_conn: AtomicU64,
    epoch: tokio::time::Instant,
    /// Open connections per peer IP (`limits.max_connections_per_addr`).
    per_addr: Mutex<HashMap<IpAddr, usize>>,
}

/// One connection's count in `Shared::per_addr`, released on drop.
struct AddrSlot {
    shared: Arc<Shared>,
    ip: IpAddr,
}

impl Drop for AddrSlot {
    fn drop(&mut self) {
        let mut map = self.shared.per_addr.lock().expect("per_addr lock poisoned");
        if let Some(n) = map.get_mut(&self.ip) {
            *n -= 1;
            if *n == 0 {
                map.remove(&self.ip);
            }
        }
    }
}

impl Shared {
    fn claim_addr(self: &Arc<Self>, ip: IpAddr) -> Option<AddrSlot> {
        let mut map = self.per_addr.lock().expect("per_addr lock poisoned");
        let n = map.entry(ip).or_insert(0);
        if *n >= self.config.limits.max_connections_per_addr {
            return None;
        }
        *n += 1;
        Some(AddrSlot {
            shared: self.clone(),
            ip,
        })
    }
}

#[derive(Default)]
struct Registry {
    next_id: u64,
    matches: BTreeMap<MatchId, MatchEntry>,
}

impl Shared {
    pub(crate) fn shutdown_signal(&self) -> watch::Receiver<bool> {
        self.shutdown.clone()
    }

    /// Creates a match and spawns its task.
    pub(crate) fn create_match(&self, req: &CreateMatch) -> Result<MatchInfo, ErrorMsg> {
        let cfg = &self.config;
        let mut match_cfg = cfg.match_cfg.clone();
        if let Some(min) = req.minutes {
            if !(min.is_finite() && min > 0.0 && min <= 24.0 * 60.0) {
                return Err(invalid(format!("minutes {min} not in (0, 1440]")));
            }
            match_cfg.minutes = min;
        }
        let start_players = req.start_players.unwrap_or(cfg.start_players);
        if start_players as usize > naosoccer_proto::ROBOTS {
            return Err(invalid(format!("start_players {start_players} exceeds 8")));
        }
        let deadline_ms = req.deadline_ms.unwrap_or(cfg.deadline_ms);
        if deadline_ms == 0 || deadline_ms > 600_000 {
            return Err(invalid(format!(
                "deadline_ms {deadline_ms} not in 1..=600000"
            )));
        }
        if req.panic_at_tick.is_some() && !cfg.limits.fault_injection {
            return Err(invalid(
                "panic_at_tick is a test-only field this server does not honour".into(),
            ));
        }
        let mut reg = self.matches.lock().expect("registry lock poisoned");
        let unfinished = reg
            .matches
            .values()
            .filter(|e| e.info.borrow().state != MatchState::Finished)
            .count();
        if unfinished >= cfg.max_matches {
            return Err(ErrorMsg::new(
                ErrorCode::ResourceExhausted,
                format!("the server already runs {unfinished} matches (max_matches)"),
            ));
        }
        reg.next_id += 1;
        let id = MatchId(reg.next_id);
        let params = MatchParams {
            id,
            seed: req.seed.unwrap_or(cfg.seed.wrapping_add(id.0 - 1)),
            mode: req.mode.unwrap_or(cfg.mode),
            fill: req.fill.unwrap_or(cfg.fill),
            start_players,
            deadline: Duration::from_millis(deadline_ms),
            epoch: self.epoch,
            panic_at_tick: req.panic_at_tick,
        };
        let game = Match::new(&match_cfg, params.seed)
            .map_err(|e| invalid(format!("cannot build the match: {e}")))?;
        let info = MatchTask::initial_info(&params, &game);
        let (info_tx, info_rx) = watch::channel(info.clone());
        let (tx, rx) = mpsc::channel(MATCH_QUEUE);
        let hook = self.hooks.observer.as_ref().and_then(|f| f(&info));
        let observer = crate::recording::observer_for(&self.config, hook, &info);
        let fillers = self.hooks.fill.as_ref().map(|f| {
            naosoccer_proto::RobotId::all()
                .map(|r| f(params.seed, r))
                .collect()
        });
        let task = MatchTask::new(
            params,
            game,
            rx,
            info_tx,
            self.shutdown.clone(),
            observer,
            fillers,
        );
        let done = self.done.clone();
        tokio::spawn(async move {
            task.run().await;
            drop(done);
        });
        reg.matches.insert(id, MatchEntry { tx, info: info_rx });
        prune_finished(&mut reg);
        Ok(info)
    }

    pub(crate) fn list_matches(&self) -> Vec<MatchInfo> {
        let reg = self.matches.lock().expect("registry lock poisoned");
        reg.matches
            .values()
            .map(|e| e.info.borrow().clone())
            .collect()
    }

    /// The match to join: the named one, or the oldest unfinished one whose
    /// requested slots are free.
    pub(crate) fn find_match(
        &self,
        id: Option<MatchId>,
        team: Team,
        players: &[Player],
    ) -> Result<(MatchId, mpsc::Sender<MatchCmd>), ErrorMsg> {
        let reg = self.matches.lock().expect("registry lock poisoned");
        match id {
            Some(id) => {
                let e = reg
                    .matches
                    .get(&id)
                    .ok_or_else(|| ErrorMsg::new(ErrorCode::NotFound, format!("no match {id} on this server")))?;
                if e.info.borrow().state == MatchState::Finished {
                    return Err(ErrorMsg::new(ErrorCode::FailedPrecondition, format!("match {id} has finished")));
                }
                Ok((id, e.tx.clone()))
            }
            None => reg
                .matches
                .iter()
                .find(|(_, e)| {
                    let i = e.info.borrow();
                    i.state != MatchState::Finished && players.iter().all(|p| !i.taken.get(team)[p.index()])
                })
                .map(|(id, e)| (*id, e.tx.clone()))
                .ok_or_else(|| {
                    ErrorMsg::new(
                        ErrorCode::NotFound,
                        format!("no unfinished match has {team} player(s) {players:?} free; create one or name a match"),
                    )
                }),
        }
    }

    /// The channel of an unfinished match, for `end_match`.
    pub(crate) fn running_match(&self, id: MatchId) -> Result<mpsc::Sender<MatchCmd>, ErrorMsg> {
        let reg = self.matches.lock().expect("registry lock poisoned");
        let e = reg.matches.get(&id).ok_or_else(|| {
            ErrorMsg::new(ErrorCode::NotFound, format!("no match {id} on this server"))
        })?;
        if e.info.borrow().state == MatchState::Finished {
            let m = format!("match {id} has finished");
            return Err(ErrorMsg::new(ErrorCode::FailedPrecondition, m));
        }
        Ok(e.tx.clone())
    }

    pub(crate) fn task_guard(&self) -> mpsc::Sender<()> {
        self.done.clone()
    }
}

fn invalid(message: String) -> ErrorMsg {
    ErrorMsg::new(ErrorCode::InvalidArgument, message)
}

fn prune_finished(reg: &mut Registry) {
    let finished: Vec<MatchId> = reg
        .matches
        .iter()
        .filter(|(_, e)| e.info.borrow().state == MatchState::Finished)
        .map(|(id, _)| *id)
        .collect();
    for id in finished
        .iter()
        .take(finished.len().saturating_sub(KEEP_FINISHED))
    {
        reg.matches.remove(id);
    }
}

/// Serves until `shutdown` completes, then stops every match (clients get
/// `match_end` with reason `shutdown`, then an `unavailable` error) and
/// returns once all connections and matches are done.
pub async fn run(
    listener: TcpListener,
    config: ServerConfig,
    shutdown: impl Future,
) -> Result<(), ServerError> {
    run_with(listener, config, Hooks::default(), shutdown).await
}

/// [`run`] with extension points (per-match observers).
pub async fn run_with(
    listener: TcpListener,
    mut config: ServerConfig,
    hooks: Hooks,
    shutdown: impl Future,
) -> Result<(), ServerError> {
    config.validate()?;
    let tokens = config.resolve_tokens();
    let (shutdown_tx, shutdown_rx) = watch::channel(false);
    let (done_tx, mut done_rx) = mpsc::channel::<()>(1);
    let limit = Arc::new(Semaphore::new(config.max_connections));
    let auto_matches = config.matches;
    let shared = Arc::new(Shared {
        config,
        tokens,
        hooks,
        matches: Mutex::new(Registry::default()),
        shutdown: shutdown_rx,
        done: done_tx,
        next_conn: AtomicU64::new(1),
        epoch: tokio::time::Instant::now(),
        per_addr: Mutex::new(HashMap::new()),
    });
    for _ in 0..auto_matches {
        shared.create_match(&CreateMatch::default()).map_err(|e| {
            ServerError::Io(std::io::Error::other(format!(
                "creating the configured matches: {e}"
            )))
        })?;
    }
    tracing::info!(addr = ?listener.local_addr().ok(), matches = auto_matches, "serving");

    tokio::pin!(shutdown);
    loop {
        let accepted = tokio::select! {
            _ = &mut shutdown => break,
            a = listener.accept() => a,
        };
        let (stream, peer) = match accepted {
            Ok(a) => a,
            Err(e) => {
                // Out of file descriptors and the like: back off instead of spinning.
                tracing::error!(error = %e, "accept failed");
                tokio::time::sleep(Duration::from_millis(100)).await;
                continue;
            }
        };
        let id = shared.next_conn.fetch_add(1, Ordering::Relaxed);
        let Ok(permit) = limit.clone().try_acquire_owned() else {
            tracing::warn!(%peer, "connection limit reached; refusing");
            let m = "the server is at its connection limit (max_connections); try again later";
            tokio::spawn(refuse(stream, m, shared.task_guard()));
            continue;
        };
        let Some(addr_slot) = shared.claim_addr(peer.ip()) else {
            tracing::warn!(%peer, "per-address connection limit reached; refusing");
            let m = "too many connections from your address (max_connections_per_addr)";
            tokio::spawn(refuse(stream, m, shared.task_guard()));
            continue;
        };
        set_keepalive(&stream, shared.config.limits.keepalive_s);
        let conn_shared = shared.clone();
        tokio::spawn(async move {
            let guard = conn_shared.task_guard();
            connection::serve(stream, peer, id, conn_shared).await;
            drop((permit, addr_slot, guard));
        });
    }

    tracing::info!("shutting down");
    drop(listener);
    let _ = shutdown_tx.send(true);
    drop(shared);
    // Every task holds a `done` sender; recv yields None once all have ended.
    let _ = done_rx.recv().await;
    tracing::info!("shut down");
    Ok(())
}

/// Dead peers (a machine that vanished) are found by the kernel's probes.
fn set_keepalive(stream: &TcpStream, secs: u64) {
    if secs == 0 {
        return;
    }
    let ka = socket2::TcpKeepalive::new().with_time(Duration::from_secs(secs));
    if let Err(e) = socket2::SockRef::from(stream).set_tcp_keepalive(&ka) {
        tracing::debug!(error = %e, "cannot set TCP keepalive");
    }
}

async fn refuse(mut stream: TcpStream, message: &'static str, guard: mpsc::Sender<()>) {
    let e = ErrorMsg::new(ErrorCode::ResourceExhausted, message).fatal();
    if let Ok(bytes) = encode(&ServerMsg::Error(e)) {
        // A refused peer that does not read cannot hold this task long.
        let _ = tokio::time::timeout(Duration::from_secs(5), stream.write_all(&bytes)).await;
    }
    let _ = stream.shutdown().await;
    drop(guard);
}
