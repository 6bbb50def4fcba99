//! One task per match owns its [`Match`]: connections talk to it only over
//! channels (joins, leaves, actions in; observations, match end out), so no
//! lock guards the world.
//!
//! Lockstep: the task sends every joined connection its observations, then
//! waits until each client-controlled robot has an action for the tick or
//! the deadline passes (a missing action is `stay` and a counted miss), then
//! steps. Real time: ticks start at fixed instants; the latest action a robot
//! sent by then is applied (late ones apply at the next tick), no action is a
//! miss. Slots no client ever joined are played by the fill policy; a robot
//! whose client left stands.

use crate::observer::{MatchObserver, TickRecord};
use naosoccer_client::{Policy, PolicyKind};
use naosoccer_proto::msg::{
    EndReason, ErrorCode, ErrorMsg, Fill, Frame, Joined, MatchEnd, MatchId, MatchInfo, MatchState,
    Mode, PerTeam, Pitch, Player, Score,
};
use naosoccer_proto::{Action, Event, Observation, RobotId, Team, PLAYERS_PER_TEAM, ROBOTS};
use naosoccer_referee::Match;
use std::sync::Arc;
use std::time::Duration;
use tokio::sync::{mpsc, oneshot, watch};
use tokio::time::Instant;

pub(crate) type ConnId = u64;

/// A connection the match dropped because its queue was full: it learns why
/// through this (its queue has no room for the news).
pub(crate) type Kick = oneshot::Sender<ErrorMsg>;

/// From a match task to one connection. Observations, the common case, are
/// inline so that a tick allocates nothing.
#[derive(Debug)]
#[allow(clippy::large_enum_variant)]
pub(crate) enum Outgoing {
    Observation {
        match_id: MatchId,
        tick: u64,
        len: u8,
        obs: [Observation; PLAYERS_PER_TEAM],
        /// The events of the tick that led here, shared by every connection.
        events: Arc<Vec<Event>>,
    },
    MatchEnd(MatchEnd),
    Error(ErrorMsg),
}

/// From a connection to a match task.
#[derive(Debug)]
pub(crate) enum MatchCmd {
    Join {
        conn: ConnId,
        team: Team,
        players: Vec<Player>,
        out: mpsc::Sender<Outgoing>,
        kick: Kick,
        reply: oneshot::Sender<Result<Joined, ErrorMsg>>,
    },
    /// The connection left or closed; its robots stand from now on.
    Leave { conn: ConnId },
    /// End the match now (`end_match`): its clients get their `match_end`,
    /// then the reply carries the final description.
    End { reply: oneshot::Sender<MatchInfo> },
    /// Validated by the connection: only players it controls.
    Action {
        conn: ConnId,
        team: Team,
        tick: u64,
        actions: [Option<Action>; PLAYERS_PER_TEAM],
    },
}

/// Per-match settings, resolved from the server config and `create_match`.
#[derive(Debug, Clone)]
pub(crate) struct MatchParams {
    pub id: MatchId,
    pub seed: u64,
    pub mode: Mode,
    pub fill: Fill,
    pub start_players: u8,
    pub deadline: Duration,
    /// The server's start: real-time matches schedule their ticks from it.
    pub epoch: Instant,
    /// Fault injection (tests only): panic when this tick is played.
    pub panic_at_tick: Option<u64>,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Slot {
    /// Never joined: the fill policy plays it.
    Open,
    Client(ConnId),
    /// Its client left: the robot stands.
    Vacated,
}

struct ConnEntry {
    id: ConnId,
    team: Team,
    players: Vec<Player>,
    /// Bounded (`limits.max_outbound`): a connection whose queue is full is
    /// not reading and is dropped rather than buffered for or waited on.
    out: mpsc::Sender<Outgoing>,
    kick: Option<Kick>,
}

pub(crate) struct MatchTask {
    params: MatchParams,
    game: Match,
    slots: [Slot; ROBOTS],
    conns: Vec<ConnEntry>,
    fillers: Vec<Option<Box<dyn Policy>>>,
    /// This tick's actions and which client-controlled robots have answered.
    actions: [Action; ROBOTS],
    answered: [bool; ROBOTS],
    /// Real time: the newest action received per robot and its tick.
    pending: [Option<(u64, Action)>; ROBOTS],
    misses: [u64; ROBOTS],
    /// The tick whose observation went out last (actions may name it or older).
    observed: Option<u64>,
    rx: mpsc::Receiver<MatchCmd>,
    info: watch::Sender<MatchInfo>,
    shutdown: watch::Receiver<bool>,
    observer: Option<Box<dyn MatchObserver>>,
    obs_scratch: Observation,
    /// The events of the last tick played; they go out with the next
    /// observation (or the match end). Reused while no connection still
    /// holds the previous tick's.
    events: Arc<Vec<Event>>,
    lateness_us: Vec<u32>,
    /// Who asked to end the match early, if anyone: told once it has ended.
    ended_by: Option<oneshot::Sender<MatchInfo>>,
}

enum Stop {
    Finished,
    Shutdown,
    /// A tick panicked: the match cannot go on, the server can.
    Panicked,
    /// An admin ended it (`end_match`).
    Ended,
}

impl MatchTask {
    pub(crate) fn new(
        params: MatchParams,
        game: Match,
        rx: mpsc::Receiver<MatchCmd>,
        info: watch::Sender<MatchInfo>,
        shutdown: watch::Receiver<bool>,
        observer: Option<Box<dyn MatchObserver>>,
        custom_fill: Option<Vec<Box<dyn Policy>>>,
    ) -> MatchTask {
        let kind = match params.fill {
            Fill::Scripted => PolicyKind::Scripted,
            Fill::Idle => PolicyKind::Idle,
        };
        let fillers = match custom_fill {
            Some(policies) => policies.into_iter().map(Some).collect(),
            None => RobotId::all()
                .map(|r| Some(kind.build(params.seed, r)))
                .collect(),
        };
        let obs_scratch = game.observe(Team::Blue, 0);
        MatchTask {
            params,
            game,
            slots: [Slot::Open; ROBOTS],
            conns: Vec::new(),
            fillers,
            actions: [Action::Stay; ROBOTS],
            answered: [false; ROBOTS],
            pending: [None; ROBOTS],
            misses: [0; ROBOTS],
            observed: None,
            rx,
            info,
            shutdown,
            observer,
            obs_scratch,
            events: Arc::new(Vec::with_capacity(16)),
            lateness_us: Vec::new(),
            ended_by: None,
        }
    }

    /// The first `MatchInfo` of a match (before its task runs).
    pub(crate) fn initial_info(params: &MatchParams, game: &Match) -> MatchInfo {
        MatchInfo {
            match_id: params.id,
            state: MatchState::Waiting,
            mode: params.mode,
            fill: params.fill,
            seed: params.seed,
            control_hz: game.config().control_hz,
            tick: game.tick(),
            total_ticks: game.total_ticks(),
            deadline_ms: params.deadline.as_millis() as u64,
            start_players: params.start_players,
            score: Score::default(),
            taken: PerTeam::default(),
        }
    }

    pub(crate) async fn run(mut self) {
        let id = self.params.id;
        tracing::info!(match_id = %id, seed = self.params.seed, mode = %self.params.mode, "match created");
        let stop = self.play().await;
        let reason = match stop {
            Stop::Finished => EndReason::Finished,
            Stop::Shutdown => EndReason::Shutdown,
            Stop::Panicked => EndReason::Internal,
            Stop::Ended => EndReason::Ended,
        };
        let (blue, red) = self.game.score();
        let end = MatchEnd {
            match_id: id,
            reason,
            tick: self.game.tick(),
            score: Score { blue, red },
            stats: self.game.stats(),
            misses: self.misses_per_team(),
            rewards: PerTeam {
                blue: self.game.rewards(Team::Blue),
                red: self.game.rewards(Team::Red),
            },
            events: self.unsent_events(reason),
            state_hash: format!("{:016x}", self.game.state_hash()),
        };
        if reason == EndReason::Internal {
            tracing::error!(match_id = %id, tick = end.tick, "match task panicked; ending the match");
            let e = ErrorMsg::new(
                ErrorCode::Internal,
                format!("match {id} failed inside the server at tick {}; it has ended (the server goes on)", end.tick),
            );
            for c in &self.conns {
                deliver(&c.out, Outgoing::Error(e.clone()));
            }
        }
        tracing::info!(
            match_id = %id,
            ?reason,
            ticks = end.tick,
            blue = blue,
            red = red,
            misses = ?self.misses,
            lateness_p99_us = percentile(&mut self.lateness_us, 0.99),
            "match ended: blue {blue} - {red} red"
        );
        if let Some(o) = &mut self.observer {
            // An observer that panicked mid-tick may panic again here; the
            // clients still get their match_end.
            let finish = std::panic::AssertUnwindSafe(|| o.on_end(&end, &self.game));
            if std::panic::catch_unwind(finish).is_err() {
                tracing::error!(match_id = %id, "the match observer panicked in on_end");
            }
        }
        // Finished before anyone hears of it, so a client that lists matches
        // right after its match_end sees it finished.
        self.info.send_modify(|i| {
            i.state = MatchState::Finished;
            i.taken = PerTeam::default();
        });
        for c in self.conns.drain(..) {
            deliver(&c.out, Outgoing::MatchEnd(end.clone()));
        }
        if let Some(reply) = self.ended_by.take() {
            let _ = reply.send(self.info.borrow().clone());
        }
    }

    async fn play(&mut self) -> Stop {
        while self.joined_robots() < self.params.start_players as usize {
            tokio::select! {
                biased;
                _ = self.shutdown.changed() => return Stop::Shutdown,
                cmd = self.rx.recv() => match cmd {
                    Some(cmd) => if let Some(stop) = self.handle(cmd) {
                        return stop;
                    },
                    None => return Stop::Shutdown,
                },
            }
        }
        self.info.send_modify(|i| i.state = MatchState::Running);
        tracing::info!(match_id = %self.params.id, "match started");
        if let Some(o) = &mut self.observer {
            o.on_start(&self.info.borrow(), &self.game);
        }
        match self.params.mode {
            Mode::Lockstep => self.lockstep().await,
            Mode::Realtime => self.realtime().await,
        }
    }

    async fn lockstep(&mut self) -> Stop {
        while !self.game.is_finished() {
            let tick = self.game.tick();
            self.answered = [false; ROBOTS];
            self.actions = [Action::Stay; ROBOTS];
            self.send_observations(tick);
            let deadline = tokio::time::sleep(self.params.deadline);
            tokio::pin!(deadline);
            while self.waiting_for_clients() {
                tokio::select! {
                    biased;
                    _ = self.shutdown.changed() => return Stop::Shutdown,
                    cmd = self.rx.recv() => match cmd {
                        Some(cmd) => if let Some(stop) = self.handle(cmd) {
                        return stop;
                    },
                        None => return Stop::Shutdown,
                    },
                    _ = &mut deadline => break,
                }
            }
            for r in 0..ROBOTS {
                if matches!(self.slots[r], Slot::Client(_)) && !self.answered[r] {
                    self.misses[r] += 1;
                }
            }
            if !self.guarded_step(tick, None) {
                return Stop::Panicked;
            }
            // A match with no clients never waits; let the other tasks on
            // this worker run between ticks.
            tokio::task::consume_budget().await;
        }
        Stop::Finished
    }

    async fn realtime(&mut self) -> Stop {
        let period = Duration::from_secs_f64(1.0 / f64::from(self.game.config().control_hz));
        self.lateness_us
            .reserve(self.game.total_ticks().saturating_sub(self.game.tick()) as usize);
        // Matches tick at staggered phases of the period (golden-ratio
        // spacing by id), so many real-time matches do not all wake, step and
        // encode at the same instant and delay each other's ticks.
        let frac = (self.params.id.0 as f64 * 0.618_033_988_749_895).fract();
        let phase = period.mul_f64(frac);
        let since = Instant::now().saturating_duration_since(self.params.epoch + phase);
        let periods = since.as_nanos().div_ceil(period.as_nanos().max(1)) as u32;
        let mut next = self.params.epoch + phase + period * periods;
        tokio::time::sleep_until(next).await;
        while !self.game.is_finished() {
            let tick = self.game.tick();
            self.send_observations(tick);
            next += period;
            let sleep = tokio::time::sleep_until(next);
            tokio::pin!(sleep);
            loop {
                tokio::select! {
                    biased;
                    _ = self.shutdown.changed() => return Stop::Shutdown,
                    _ = &mut sleep => break,
                    cmd = self.rx.recv() => match cmd {
                        Some(cmd) => if let Some(stop) = self.handle(cmd) {
                        return stop;
                    },
                        None => return Stop::Shutdown,
                    },
                }
            }
            let late = Instant::now().saturating_duration_since(next);
            self.lateness_us
                .push(late.as_micros().min(u32::MAX as u128) as u32);
            for r in 0..ROBOTS {
                self.actions[r] = Action::Stay;
                if let Slot::Client(_) = self.slots[r] {
                    match self.pending[r].take() {
                        Some((_, a)) => self.actions[r] = a,
                        None => self.misses[r] += 1,
                    }
                }
            }
            if !self.guarded_step(tick, Some(late)) {
                return Stop::Panicked;
            }
        }
        Stop::Finished
    }

    /// [`step`](Self::step), with a panic caught so it ends only this match
    /// (false) instead of unwinding through the task. The match state after a
    /// panic is not trusted further than for the final `match_end`.
    fn guarded_step(&mut self, tick: u64, lateness: Option<Duration>) -> bool {
        let step = std::panic::AssertUnwindSafe(|| {
            if self.params.panic_at_tick == Some(tick) {
                panic!(
                    "injected fault: match {} panics at tick {tick}",
                    self.params.id
                );
            }
            self.step(tick, lateness);
        });
        std::panic::catch_unwind(step).is_ok()
    }

    /// Fill policies act, then one control tick is played.
    fn step(&mut self, tick: u64, lateness: Option<Duration>) {
        for r in RobotId::all() {
            if self.slots[r.index()] != Slot::Open {
                continue;
            }
            if let Some(p) = &mut self.fillers[r.index()] {
                self.game
                    .observe_into(r.team(), r.player(), &mut self.obs_scratch);
                self.actions[r.index()] = p.act(&self.obs_scratch);
            }
        }
        let events = self.game.step(&self.actions);
        // `step` lends its events from a `&mut` borrow; the observer also
        // needs the match, and the clients get them with the next
        // observation, so they go through a reused buffer.
        match Arc::get_mut(&mut self.events) {
            Some(buf) => {
                buf.clear();
                buf.extend_from_slice(events);
            }
            None => self.events = Arc::new(events.to_vec()),
        }
        if let Some(o) = &mut self.observer {
            o.on_tick(&TickRecord {
                game: &self.game,
                tick,
                actions: &self.actions,
                events: &self.events,
                lateness,
            });
        }
        let (blue, red) = self.game.score();
        let now = self.game.tick();
        self.info.send_modify(|i| {
            i.tick = now;
            i.score = Score { blue, red };
        });
    }

    fn joined_robots(&self) -> usize {
        self.slots
            .iter()
            .filter(|s| matches!(s, Slot::Client(_)))
            .count()
    }

    fn waiting_for_clients(&self) -> bool {
        (0..ROBOTS).any(|r| matches!(self.slots[r], Slot::Client(_)) && !self.answered[r])
    }

    fn send_observations(&mut self, tick: u64) {
        self.observed = Some(tick);
        let mut i = 0;
        while i < self.conns.len() {
            let c = &self.conns[i];
            if send_observation(
                &self.game,
                &self.obs_scratch,
                &self.events,
                self.params.id,
                tick,
                c,
            ) {
                i += 1;
                continue;
            }
            let id = c.id;
            let queued = c.out.max_capacity();
            if let Some(mut c) = self.remove_conn(id) {
                tracing::warn!(match_id = %self.params.id, conn = id, tick, queued, "client is not reading; dropped from the match, its robots stand");
                let m = format!(
                    "you fell {queued} messages behind in match {}; dropped from the match (its robots stand), closing the connection",
                    self.params.id
                );
                if let Some(k) = c.kick.take() {
                    let _ = k.send(ErrorMsg::new(ErrorCode::ResourceExhausted, m).fatal());
                }
            }
        }
    }

    /// Takes a connection out of the match; its robots stand from now on.
    fn remove_conn(&mut self, conn: ConnId) -> Option<ConnEntry> {
        let i = self.conns.iter().position(|c| c.id == conn)?;
        let c = self.conns.swap_remove(i);
        for p in &c.players {
            let r = robot(c.team, *p).index();
            self.slots[r] = Slot::Vacated;
            self.pending[r] = None;
        }
        self.publish_taken();
        Some(c)
    }

    /// Applies one command; `Some` when it ends the match.
    fn handle(&mut self, cmd: MatchCmd) -> Option<Stop> {
        match cmd {
            MatchCmd::End { reply } => {
                tracing::info!(match_id = %self.params.id, tick = self.game.tick(), "ended by an admin");
                self.ended_by = Some(reply);
                return Some(Stop::Ended);
            }
            MatchCmd::Join {
                conn,
                team,
                players,
                out,
                kick,
                reply,
            } => {
                let taken: Vec<String> = players
                    .iter()
                    .filter(|p| matches!(self.slots[robot(team, **p).index()], Slot::Client(_)))
                    .map(|p| p.to_string())
                    .collect();
                if !taken.is_empty() {
                    let msg = format!(
                        "{team} player(s) {} of match {} already controlled by another connection",
                        taken.join(", "),
                        self.params.id
                    );
                    let _ = reply.send(Err(ErrorMsg::new(ErrorCode::FailedPrecondition, msg)));
                    return None;
                }
                let joined = Joined {
                    match_id: self.params.id,
                    team,
                    players: players.clone(),
                    seed: self.params.seed,
                    mode: self.params.mode,
                    control_hz: self.game.config().control_hz,
                    total_ticks: self.game.total_ticks(),
                    deadline_ms: self.params.deadline.as_millis() as u64,
                    pitch: Some(pitch(&self.game)),
                };
                if reply.send(Ok(joined)).is_err() {
                    return None; // the connection went away meanwhile
                }
                // Joining mid-tick: the tick waits for the answers of the
                // robots that still owe one and the connection gets the
                // tick's observation below. A robot whose previous client
                // already answered this tick (it left, or lost its
                // connection, while the tick waited on others) keeps that
                // action: sending the tick again would ask for a second
                // answer to an answered tick, so such a connection's first
                // observation is the next tick's (issue 15 A.5).
                let mut owes = false;
                for p in &players {
                    let r = robot(team, *p).index();
                    self.slots[r] = Slot::Client(conn);
                    self.pending[r] = None;
                    owes |= !self.answered[r];
                }
                let entry = ConnEntry {
                    id: conn,
                    team,
                    players,
                    out,
                    kick: Some(kick),
                };
                tracing::info!(match_id = %self.params.id, conn, %team, players = ?entry.players, "joined");
                let answered = self.params.mode == Mode::Lockstep && !owes;
                if let (Some(tick), false) = (self.observed, answered) {
                    send_observation(
                        &self.game,
                        &self.obs_scratch,
                        &self.events,
                        self.params.id,
                        tick,
                        &entry,
                    );
                }
                self.conns.push(entry);
                self.publish_taken();
            }
            MatchCmd::Leave { conn } => {
                if let Some(c) = self.remove_conn(conn) {
                    tracing::info!(match_id = %self.params.id, conn, team = %c.team, players = ?c.players, "left; its robots stand");
                }
            }
            MatchCmd::Action {
                conn,
                team,
                tick,
                actions,
            } => {
                // From a connection no longer in the match: nothing to do.
                let c = self.conns.iter().find(|c| c.id == conn)?;
                let current = self.observed.unwrap_or(0);
                if self.params.mode == Mode::Lockstep && tick < current {
                    let e = ErrorMsg {
                        code: ErrorCode::DeadlineExceeded,
                        message: format!("tick {tick} was already played (now at tick {current}); the robot stayed"),
                        fatal: false,
                        in_reply_to: Some("action".into()),
                        tick: Some(tick),
                    };
                    deliver(&c.out, Outgoing::Error(e));
                    return None;
                }
                for (p, a) in actions.iter().enumerate() {
                    let Some(a) = *a else { continue };
                    let r = team.index() * PLAYERS_PER_TEAM + p;
                    if self.slots[r] != Slot::Client(conn) {
                        continue;
                    }
                    match self.params.mode {
                        Mode::Lockstep => {
                            self.actions[r] = a;
                            self.answered[r] = true;
                        }
                        Mode::Realtime => {
                            if self.pending[r].is_none_or(|(t, _)| t <= tick) {
                                self.pending[r] = Some((tick, a));
                            }
                        }
                    }
                }
            }
        }
        None
    }

    fn publish_taken(&self) {
        let mut taken = PerTeam::<[bool; PLAYERS_PER_TEAM]>::default();
        for r in RobotId::all() {
            taken.get_mut(r.team())[r.player()] = matches!(self.slots[r.index()], Slot::Client(_));
        }
        self.info.send_modify(|i| i.taken = taken);
    }

    /// The events `match_end` carries: the last tick's, unless an
    /// observation already took them out (a match ended between ticks) or
    /// the match failed.
    fn unsent_events(&self, reason: EndReason) -> Vec<Event> {
        let sent = self.observed == Some(self.game.tick());
        if sent || reason == EndReason::Internal {
            Vec::new()
        } else {
            self.events.to_vec()
        }
    }

    fn misses_per_team(&self) -> PerTeam<[u64; PLAYERS_PER_TEAM]> {
        let mut m = PerTeam::<[u64; PLAYERS_PER_TEAM]>::default();
        for r in RobotId::all() {
            m.get_mut(r.team())[r.player()] = self.misses[r.index()];
        }
        m
    }
}

/// The pitch as `joined` announces it (protocol 1.2).
fn pitch(game: &Match) -> Pitch {
    let cfg = game.config();
    Pitch {
        field_length: cfg.sim.field_length,
        field_width: cfg.sim.field_width,
        goal_width: cfg.sim.goal_width,
        goal_depth: cfg.sim.goal_depth,
        goal_height: cfg.sim.goal_height,
        ball_radius: cfg.sim.ball_radius,
        b_d: cfg.rules.b_d,
        b_rad: cfg.rules.b_rad,
        frame: Frame::Team,
    }
}

fn robot(team: Team, p: Player) -> RobotId {
    RobotId::new(team, p.index()).expect("Player is always < PLAYERS_PER_TEAM")
}

/// False if the connection's queue is full (it is not reading).
fn send_observation(
    game: &Match,
    template: &Observation,
    events: &Arc<Vec<Event>>,
    match_id: MatchId,
    tick: u64,
    c: &ConnEntry,
) -> bool {
    let mut obs: [Observation; PLAYERS_PER_TEAM] = std::array::from_fn(|_| template.clone());
    for (slot, p) in obs.iter_mut().zip(&c.players) {
        game.observe_into(c.team, p.index(), slot);
    }
    let msg = Outgoing::Observation {
        match_id,
        tick,
        len: c.players.len() as u8,
        obs,
        events: Arc::clone(events),
    };
    !matches!(c.out.try_send(msg), Err(mpsc::error::TrySendError::Full(_)))
}

/// Sends a message that must arrive (match end, errors) without blocking the
/// match on a slow reader.
fn deliver(out: &mpsc::Sender<Outgoing>, msg: Outgoing) {
    if let Err(mpsc::error::TrySendError::Full(msg)) = out.try_send(msg) {
        let out = out.clone();
        tokio::spawn(async move {
            let _ = out.send(msg).await;
        });
    }
}

fn percentile(v: &mut [u32], q: f64) -> Option<u32> {
    if v.is_empty() {
        return None;
    }
    v.sort_unstable();
    let i = ((v.len() - 1) as f64 * q).round() as usize;
    Some(v[i])
}
