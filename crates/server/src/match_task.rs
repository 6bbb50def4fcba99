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

mod commands;
mod end;
mod info;

use crate::match_msg::{send_observation, ConnEntry, ConnId, MatchCmd};
use crate::observer::{MatchObserver, TickRecord};
use crate::shared::Listing;
use naosoccer_policy::ScriptedParams;
use naosoccer_policy::{Policy, PolicyKind};
use naosoccer_proto::msg::{ErrorCode, ErrorMsg, Fill, MatchId, MatchInfo, MatchState, Mode};
use naosoccer_proto::{Action, Event, Observation, RobotId, StateChange, Team, Tick, ROBOTS};
use naosoccer_referee::{Ending, Judge, Match};
use std::future::Future;
use std::pin::Pin;
use std::sync::Arc;
use std::task::{Context, Poll};
use std::time::Duration;
use tokio::sync::{mpsc, oneshot, watch};
use tokio::time::{Instant, Sleep};

/// Per-match settings, resolved from the server config and `create_match`.
#[derive(Debug, Clone)]
pub(crate) struct MatchParams {
    pub id: MatchId,
    pub seed: u64,
    pub mode: Mode,
    pub fill: Fill,
    /// The trained team that plays the open slots instead of `fill`.
    pub fill_team: Option<String>,
    pub start_players: u8,
    pub deadline: Duration,
    /// The server's start: real-time matches schedule their ticks from it.
    pub epoch: Instant,
    /// Fault injection (tests only): panic when this tick is played.
    pub panic_at_tick: Option<u64>,
    /// A match created from a scenario: the judge of its play, which ends
    /// the match when the play ends.
    pub judge: Option<Judge>,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Slot {
    /// Never joined: the fill policy plays it.
    Open,
    Client(ConnId),
    /// Its client left: the robot stands.
    Vacated,
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
    pending: [Option<(Tick, Action)>; ROBOTS],
    misses: [u64; ROBOTS],
    /// The tick whose observation went out last (actions may name it or older).
    observed: Option<Tick>,
    rx: mpsc::Receiver<MatchCmd>,
    listing: Listing,
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
    /// Whether the match has started (its observer told).
    started: bool,
    /// State changes (`set_state`) accepted before the match started:
    /// applied, in order, when it starts, after the observer saw the start.
    queued: Vec<StateChange>,
    /// The tick the match started from (a scenario's start tick, else 0).
    first_tick: Tick,
    /// How the scenario's play ended, once it has.
    ending: Option<Ending>,
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
        listing: Listing,
        shutdown: watch::Receiver<bool>,
        observer: Option<Box<dyn MatchObserver>>,
        custom_fill: Option<Vec<Box<dyn Policy>>>,
    ) -> MatchTask {
        let kind = match params.fill {
            // On this match's pitch (the defaults on the default pitch).
            Fill::Scripted => PolicyKind::scripted_with(ScriptedParams::for_pitch(&game.pitch())),
            Fill::Idle => PolicyKind::Idle,
            // Levels 1..=5 only: the protocol refuses others.
            Fill::ScriptedLevel(n) => ScriptedParams::level_for_pitch(n, &game.pitch())
                .map_or(PolicyKind::Scripted, PolicyKind::scripted_with),
        };
        let fillers = match custom_fill {
            Some(policies) => policies.into_iter().map(Some).collect(),
            None => RobotId::all()
                .map(|r| Some(kind.build(params.seed, r)))
                .collect(),
        };
        let obs_scratch = game.observe(Team::Blue, 0);
        let first_tick = game.tick();
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
            listing,
            shutdown,
            observer,
            obs_scratch,
            events: Arc::new(Vec::with_capacity(16)),
            lateness_us: Vec::new(),
            ended_by: None,
            started: false,
            queued: Vec::new(),
            first_tick,
            ending: None,
        }
    }

    pub(crate) async fn run(mut self) {
        let id = self.params.id;
        tracing::info!(match_id = %id, seed = self.params.seed, mode = %self.params.mode, "match created");
        let stop = self.play().await;
        self.finish(stop);
    }

    async fn play(&mut self) -> Stop {
        let start = self.params.start_players as usize;
        if let Err(stop) = self.serve(None, |t| t.joined_robots() < start).await {
            return stop;
        }
        self.listing
            .info
            .send_modify(|i| i.state = MatchState::Running);
        tracing::info!(match_id = %self.params.id, "match started");
        if let Some(o) = &mut self.observer {
            o.on_start(&self.listing.info.borrow(), &self.game);
        }
        self.started = true;
        for change in std::mem::take(&mut self.queued) {
            self.apply_state(&change);
        }
        match self.params.mode {
            Mode::Lockstep => self.lockstep().await,
            Mode::Realtime => self.realtime().await,
        }
    }

    /// Applies commands while `waiting` holds and, if there is one, until the
    /// timer fires; `Err` when the match must stop (shutdown, every sender
    /// gone, `end_match`). The one place the task waits for commands.
    ///
    /// A shutdown comes first. A lockstep deadline comes after the commands
    /// already queued, so an action that arrived in time counts; a real-time
    /// tick comes before them, so the tick starts on time whatever is queued
    /// (what arrived late applies at the next tick).
    async fn serve(
        &mut self,
        mut timer: Option<(Pin<&mut Sleep>, Mode)>,
        waiting: impl Fn(&Self) -> bool,
    ) -> Result<(), Stop> {
        enum Wake {
            Shutdown,
            Timer,
            Cmd(Option<MatchCmd>),
        }
        while waiting(self) {
            let wake = {
                let changed = self.shutdown.changed();
                tokio::pin!(changed);
                let rx = &mut self.rx;
                std::future::poll_fn(|cx| {
                    if changed.as_mut().poll(cx).is_ready() {
                        return Poll::Ready(Wake::Shutdown);
                    }
                    if fired(&mut timer, true, cx) {
                        return Poll::Ready(Wake::Timer);
                    }
                    if let Poll::Ready(cmd) = rx.poll_recv(cx) {
                        return Poll::Ready(Wake::Cmd(cmd));
                    }
                    if fired(&mut timer, false, cx) {
                        return Poll::Ready(Wake::Timer);
                    }
                    Poll::Pending
                })
                .await
            };
            match wake {
                Wake::Shutdown | Wake::Cmd(None) => return Err(Stop::Shutdown),
                Wake::Timer => return Ok(()),
                Wake::Cmd(Some(cmd)) => {
                    if let Some(stop) = self.handle(cmd) {
                        return Err(stop);
                    }
                }
            }
        }
        Ok(())
    }

    /// Whether the match plays on: its clock has not run out and its
    /// scenario's play (if any) has not ended.
    fn playing(&self) -> bool {
        !self.game.is_finished() && self.ending.is_none()
    }

    async fn lockstep(&mut self) -> Stop {
        while self.playing() {
            let tick = self.game.tick();
            self.answered = [false; ROBOTS];
            self.actions = [Action::Stay; ROBOTS];
            self.send_observations(tick);
            let deadline = tokio::time::sleep(self.params.deadline);
            tokio::pin!(deadline);
            let timer = Some((deadline.as_mut(), Mode::Lockstep));
            if let Err(stop) = self.serve(timer, Self::waiting_for_clients).await {
                return stop;
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
        self.lateness_us.reserve(
            self.game
                .total_ticks()
                .saturating_sub(self.game.tick().get()) as usize,
        );
        // Matches tick at staggered phases of the period (golden-ratio
        // spacing by id), so many real-time matches do not all wake, step and
        // encode at the same instant and delay each other's ticks.
        let frac = (self.params.id.0 as f64 * 0.618_033_988_749_895).fract();
        let phase = period.mul_f64(frac);
        let since = Instant::now().saturating_duration_since(self.params.epoch + phase);
        let periods = since.as_nanos().div_ceil(period.as_nanos().max(1)) as u32;
        let mut next = self.params.epoch + phase + period * periods;
        tokio::time::sleep_until(next).await;
        while self.playing() {
            let tick = self.game.tick();
            self.send_observations(tick);
            next += period;
            let sleep = tokio::time::sleep_until(next);
            tokio::pin!(sleep);
            let timer = Some((sleep.as_mut(), Mode::Realtime));
            if let Err(stop) = self.serve(timer, |_| true).await {
                return stop;
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
    fn guarded_step(&mut self, tick: Tick, lateness: Option<Duration>) -> bool {
        let step = std::panic::AssertUnwindSafe(|| {
            if self.params.panic_at_tick == Some(tick.get()) {
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
    fn step(&mut self, tick: Tick, lateness: Option<Duration>) {
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
        if let Some(j) = &self.params.judge {
            self.ending = j.check(&self.game, &self.events);
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
        let score = self.game.score();
        let now = self.game.tick();
        self.listing.info.send_modify(|i| {
            i.tick = now;
            i.score = score;
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

    fn send_observations(&mut self, tick: Tick) {
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
                tracing::warn!(match_id = %self.params.id, conn = id, tick = tick.get(), queued, "client is not reading; dropped from the match, its robots stand");
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
}

/// Whether `timer` fired, polled only on its turn: before the commands
/// (`first`) in real time, after them in lockstep.
fn fired(timer: &mut Option<(Pin<&mut Sleep>, Mode)>, first: bool, cx: &mut Context<'_>) -> bool {
    match timer {
        Some((t, mode)) if (*mode == Mode::Realtime) == first => t.as_mut().poll(cx).is_ready(),
        _ => false,
    }
}
