//! The match task's side of the channel: joins, leaves, actions and the
//! admin's end, applied to the task's state between ticks.

use super::{MatchTask, Slot, Stop};
use crate::match_msg::{deliver, send_observation, ConnEntry, ConnId, MatchCmd, Outgoing};
use naosoccer_proto::msg::{ErrorCode, ErrorMsg, Joined, Mode, Player};
use naosoccer_proto::{RobotId, StateChange, Tick};
use naosoccer_referee::StateError;

impl MatchTask {
    /// Takes a connection out of the match; its robots stand from now on.
    pub(super) fn remove_conn(&mut self, conn: ConnId) -> Option<ConnEntry> {
        let i = self.conns.iter().position(|c| c.id == conn)?;
        let c = self.conns.swap_remove(i);
        for p in &c.players {
            let r = RobotId::of(c.team, *p).index();
            self.slots[r] = Slot::Vacated;
            self.pending[r] = None;
        }
        self.publish_taken();
        Some(c)
    }

    /// Sets the state now (the match has started; `change` was checked)
    /// and tells the observer, so a recording re-applies it.
    pub(super) fn apply_state(&mut self, change: &StateChange) {
        let tick = self.game.tick();
        match self.game.set_state(change) {
            Ok(()) => {
                tracing::info!(match_id = %self.params.id, tick = tick.get(), "state set by an admin");
                if let Some(o) = &mut self.observer {
                    o.on_state_set(tick, change, &self.game);
                }
            }
            // Checked when it was accepted; nothing changed since that
            // could refuse it. Logged rather than trusted blindly.
            Err(e) => {
                tracing::error!(match_id = %self.params.id, error = %e, "an accepted state change was refused")
            }
        }
    }

    /// `set_state`: checked now; applied now, or when the match starts if
    /// it is still waiting for its players.
    fn set_state(&mut self, change: StateChange) -> Result<Tick, ErrorMsg> {
        let id = self.params.id;
        if self.ending.is_some() {
            let m = format!("match {id} has finished");
            return Err(ErrorMsg::new(ErrorCode::FailedPrecondition, m));
        }
        self.game.check_state(&change).map_err(|e| match e {
            StateError::Finished => ErrorMsg::new(
                ErrorCode::FailedPrecondition,
                format!("match {id} has finished"),
            ),
            e => ErrorMsg::new(ErrorCode::InvalidArgument, format!("invalid state: {e}")),
        })?;
        if self.started {
            self.apply_state(&change);
        } else {
            self.queued.push(change);
        }
        Ok(self.game.tick())
    }

    /// Applies one command; `Some` when it ends the match.
    pub(super) fn handle(&mut self, cmd: MatchCmd) -> Option<Stop> {
        match cmd {
            MatchCmd::SetState { change, reply } => {
                let _ = reply.send(self.set_state(change));
            }
            MatchCmd::End { reply } => {
                tracing::info!(match_id = %self.params.id, tick = self.game.tick().get(), "ended by an admin");
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
                    .filter(|p| {
                        matches!(self.slots[RobotId::of(team, **p).index()], Slot::Client(_))
                    })
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
                    pitch: Some(self.game.pitch()),
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
                    let r = RobotId::of(team, *p).index();
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
                let current = self.observed.unwrap_or(Tick::ZERO);
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
                for (p, a) in Player::all().zip(actions) {
                    let Some(a) = a else { continue };
                    let r = RobotId::of(team, p).index();
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
}
