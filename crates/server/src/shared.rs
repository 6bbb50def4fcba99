//! What every connection shares: the configuration, the tokens and the
//! match registry. Match state is not here: each match task owns its own;
//! this holds only the handles to reach them.

use crate::config::{ServerConfig, Tokens};
use crate::match_msg::MatchCmd;
use crate::match_task::{MatchParams, MatchTask};
use crate::observer::Hooks;
use naosoccer_proto::msg::{
    CreateMatch, ErrorCode, ErrorMsg, MatchId, MatchInfo, MatchState, Player,
};
use naosoccer_proto::Team;
use naosoccer_referee::{Match, MatchError, Scenario};
use std::collections::{BTreeMap, HashMap, VecDeque};
use std::net::IpAddr;
use std::sync::atomic::AtomicU64;
use std::sync::{Arc, Mutex, MutexGuard};
use std::time::Duration;
use tokio::sync::{mpsc, watch};

/// Finished matches kept for `list_matches`: the most recently finished;
/// the others are forgotten (docs/PROTOCOL.md, `match_list`).
const KEEP_FINISHED: usize = 64;
/// Commands queued to one match task.
const MATCH_QUEUE: usize = 256;

struct MatchEntry {
    tx: mpsc::Sender<MatchCmd>,
    info: watch::Receiver<MatchInfo>,
}

/// What every connection shares.
pub(crate) struct Shared {
    pub(crate) config: ServerConfig,
    pub(crate) tokens: Tokens,
    hooks: Hooks,
    /// Shared with every match task, which records its own end in it.
    matches: Arc<Mutex<Registry>>,
    shutdown: watch::Receiver<bool>,
    /// Each task holds a clone; `run` waits for all of them to drop.
    done: mpsc::Sender<()>,
    pub(crate) next_conn: AtomicU64,
    epoch: tokio::time::Instant,
    /// Open connections per peer IP (`limits.max_connections_per_addr`).
    per_addr: Mutex<HashMap<IpAddr, usize>>,
}

/// One connection's count in `Shared::per_addr`, released on drop.
pub(crate) struct AddrSlot {
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
    pub(crate) fn new(
        config: ServerConfig,
        tokens: Tokens,
        hooks: Hooks,
        shutdown: watch::Receiver<bool>,
        done: mpsc::Sender<()>,
    ) -> Shared {
        Shared {
            config,
            tokens,
            hooks,
            matches: Arc::new(Mutex::new(Registry::default())),
            shutdown,
            done,
            next_conn: AtomicU64::new(1),
            epoch: tokio::time::Instant::now(),
            per_addr: Mutex::new(HashMap::new()),
        }
    }

    pub(crate) fn claim_addr(self: &Arc<Self>, ip: IpAddr) -> Option<AddrSlot> {
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
    /// The finished matches still in `matches`, in the order they finished.
    finished: VecDeque<MatchId>,
    /// Matches whose id is taken but whose world is still being built
    /// (outside the lock); they count towards `max_matches`.
    starting: usize,
}

/// Why `create_match` made no match.
#[derive(Debug)]
pub(crate) enum CreateError {
    /// The request, or the server's state, does not allow it.
    Refused(ErrorMsg),
    /// The match configuration did not build (URDF, world).
    Build(MatchError),
}

impl From<ErrorMsg> for CreateError {
    fn from(e: ErrorMsg) -> CreateError {
        CreateError::Refused(e)
    }
}

impl Shared {
    pub(crate) fn shutdown_signal(&self) -> watch::Receiver<bool> {
        self.shutdown.clone()
    }

    /// Creates a match and spawns its task. The world is built with the
    /// registry unlocked (parsing the URDF and building a world takes
    /// milliseconds that every other connection's join or list would wait
    /// for): an id and a place under `max_matches` are reserved first.
    pub(crate) fn create_match(&self, req: &CreateMatch) -> Result<MatchInfo, CreateError> {
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
        // Checked before a match id is taken: a refused scenario leaves no
        // trace (protocol 1.5).
        let scenario = match &req.scenario {
            Some(text) => {
                let s = Scenario::from_toml(text, None).map_err(|e| invalid(e.to_string()))?;
                s.check(&match_cfg).map_err(|e| invalid(e.to_string()))?;
                Some((s, req.scenario_team.unwrap_or(Team::Blue)))
            }
            None if req.scenario_team.is_some() => {
                return Err(invalid(
                    "scenario_team is given without scenario".to_owned(),
                ))
            }
            None => None,
        };
        let id = {
            let mut reg = self.registry();
            let unfinished = reg.starting
                + reg
                    .matches
                    .values()
                    .filter(|e| e.info.borrow().state != MatchState::Finished)
                    .count();
            if unfinished >= cfg.max_matches {
                return Err(CreateError::Refused(ErrorMsg::new(
                    ErrorCode::ResourceExhausted,
                    format!("the server already runs {unfinished} matches (max_matches)"),
                )));
            }
            reg.next_id += 1;
            reg.starting += 1;
            MatchId(reg.next_id)
        };
        let mut params = MatchParams {
            id,
            seed: req.seed.unwrap_or(cfg.seed.wrapping_add(id.0 - 1)),
            mode: req.mode.unwrap_or(cfg.mode),
            fill: req.fill.unwrap_or(cfg.fill),
            fill_team: self.hooks.fill.as_ref().map(|f| f.spec.clone()),
            start_players,
            deadline: Duration::from_millis(deadline_ms),
            epoch: self.epoch,
            panic_at_tick: cfg.panic_at.get(&id).copied(),
            judge: None,
        };
        let built = match &scenario {
            Some((s, own)) => {
                Match::with_scenario(&match_cfg, params.seed, s, *own).inspect(|game| {
                    // The judge of its play, from its start tick.
                    params.judge = Some(s.judge(&match_cfg, *own, game.tick()));
                })
            }
            None => Match::new(&match_cfg, params.seed),
        };
        let game = match built {
            Ok(game) => game,
            Err(e) => {
                self.registry().starting -= 1;
                return Err(CreateError::Build(e));
            }
        };
        let info = MatchTask::initial_info(&params, &game);
        let (info_tx, info_rx) = watch::channel(info.clone());
        let listing = Listing {
            info: info_tx,
            registry: self.matches.clone(),
            id,
        };
        let (tx, rx) = mpsc::channel(MATCH_QUEUE);
        let hook = self.hooks.observer.as_ref().and_then(|f| f(&info));
        let observer = crate::recording::observer_for(&self.config, hook, &info);
        let fillers = self.hooks.fill.as_ref().map(|f| {
            naosoccer_proto::RobotId::all()
                .map(|r| (f.make)(params.seed, r))
                .collect()
        });
        let task = MatchTask::new(
            params,
            game,
            rx,
            listing,
            self.shutdown.clone(),
            observer,
            fillers,
        );
        {
            // Listed before its task runs: a match that ends at once is
            // then in the registry when it records its end there.
            let mut reg = self.registry();
            reg.starting -= 1;
            reg.matches.insert(id, MatchEntry { tx, info: info_rx });
        }
        let done = self.done.clone();
        tokio::spawn(async move {
            task.run().await;
            drop(done);
        });
        Ok(info)
    }

    /// The registry, for moments: nothing slow runs while it is locked.
    fn registry(&self) -> MutexGuard<'_, Registry> {
        lock(&self.matches)
    }

    pub(crate) fn list_matches(&self) -> Vec<MatchInfo> {
        let reg = self.registry();
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
        let reg = self.registry();
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
        let reg = self.registry();
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

fn invalid(message: String) -> CreateError {
    CreateError::Refused(ErrorMsg::new(ErrorCode::InvalidArgument, message))
}

fn lock(registry: &Mutex<Registry>) -> MutexGuard<'_, Registry> {
    registry.lock().expect("registry lock poisoned")
}

/// A match task's link to the registry: the [`MatchInfo`] it publishes
/// (`list_matches` reads it), and where its end is recorded.
pub(crate) struct Listing {
    pub(crate) info: watch::Sender<MatchInfo>,
    registry: Arc<Mutex<Registry>>,
    id: MatchId,
}

impl Listing {
    /// Publishes the match as finished with `publish`, and forgets the
    /// finished matches beyond the `KEEP_FINISHED` most recently finished,
    /// under one lock of the registry: no `list_matches` or `join` ever
    /// sees more of them. (Issue 39: they were forgotten only at the next
    /// `create_match`, so the list held 65 until then.)
    pub(crate) fn finish(&self, publish: impl FnOnce(&mut MatchInfo)) {
        let mut reg = lock(&self.registry);
        self.info.send_modify(publish);
        reg.finished.push_back(self.id);
        while reg.finished.len() > KEEP_FINISHED {
            if let Some(old) = reg.finished.pop_front() {
                reg.matches.remove(&old);
            }
        }
    }
}
