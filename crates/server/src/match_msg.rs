//! What passes between a match task and its connections: commands in
//! ([`MatchCmd`]), messages out ([`Outgoing`]), and the task's handle on one
//! connection ([`ConnEntry`]) with the two ways of sending to it.

use naosoccer_proto::msg::{ErrorMsg, Joined, MatchEnd, MatchId, MatchInfo, Player};
use naosoccer_proto::{Action, Event, Observation, StateChange, Team, Tick, PLAYERS_PER_TEAM};
use naosoccer_referee::Match;
use std::sync::Arc;
use tokio::sync::{mpsc, oneshot};

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
        tick: Tick,
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
    /// Set the match's state (`set_state`) before its next tick; the reply
    /// carries that tick, or why the change was refused.
    SetState {
        change: StateChange,
        reply: oneshot::Sender<Result<Tick, ErrorMsg>>,
    },
    /// Validated by the connection: only players it controls.
    Action {
        conn: ConnId,
        team: Team,
        tick: Tick,
        actions: [Option<Action>; PLAYERS_PER_TEAM],
    },
}

/// A connection as its match task holds it.
pub(crate) struct ConnEntry {
    pub(crate) id: ConnId,
    pub(crate) team: Team,
    pub(crate) players: Vec<Player>,
    /// Bounded (`limits.max_outbound`): a connection whose queue is full is
    /// not reading and is dropped rather than buffered for or waited on.
    pub(crate) out: mpsc::Sender<Outgoing>,
    pub(crate) kick: Option<Kick>,
}

/// False if the connection's queue is full (it is not reading).
pub(crate) fn send_observation(
    game: &Match,
    template: &Observation,
    events: &Arc<Vec<Event>>,
    match_id: MatchId,
    tick: Tick,
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
pub(crate) fn deliver(out: &mpsc::Sender<Outgoing>, msg: Outgoing) {
    if let Err(mpsc::error::TrySendError::Full(msg)) = out.try_send(msg) {
        let out = out.clone();
        tokio::spawn(async move {
            let _ = out.send(msg).await;
        });
    }
}
