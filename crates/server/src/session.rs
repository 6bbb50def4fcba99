//! One client's state on the server: its [`Connection`], whether it said
//! hello, its seat in a match, its rate bucket. The request handlers under
//! `cmd/` work on it; `handler` drives it.

use crate::connection::Connection;
use crate::limits::Bucket;
use crate::match_msg::{ConnId, MatchCmd, Outgoing};
use crate::shared::Shared;
use naosoccer_proto::framed::WireError;
use naosoccer_proto::msg::{
    EndReason, ErrorCode, ErrorMsg, MatchId, ObservationRef, Player, ServerMsg,
};
use naosoccer_proto::{Team, Tick};
use std::net::SocketAddr;
use std::sync::Arc;
use tokio::sync::{mpsc, oneshot};

/// The connection's seat in a match.
pub(crate) struct Seat {
    pub(crate) match_id: MatchId,
    pub(crate) team: Team,
    pub(crate) players: Vec<Player>,
    pub(crate) tx: mpsc::Sender<MatchCmd>,
    pub(crate) out: mpsc::Receiver<Outgoing>,
    /// Fires if the match dropped this connection (its queue was full).
    pub(crate) kicked: oneshot::Receiver<ErrorMsg>,
    pub(crate) kick_gone: bool,
    /// The newest tick observed; actions may not name a later one.
    pub(crate) observed: Option<Tick>,
}

pub(crate) struct Session {
    pub(crate) id: ConnId,
    pub(crate) peer: SocketAddr,
    pub(crate) shared: Arc<Shared>,
    pub(crate) conn: Connection,
    pub(crate) greeted: bool,
    /// The minor protocol version the client said in its `hello`.
    pub(crate) minor: u32,
    pub(crate) seat: Option<Seat>,
    pub(crate) joins: u32,
    pub(crate) bucket: Bucket,
}

/// Whether the connection stays open after a reply.
pub(crate) enum Flow {
    Continue,
    Close,
}

impl Session {
    pub(crate) async fn send(&mut self, msg: &ServerMsg) -> Result<(), WireError> {
        self.conn.send(msg).await
    }

    pub(crate) async fn fatal(
        &mut self,
        code: ErrorCode,
        message: String,
    ) -> Result<(), WireError> {
        let e = ErrorMsg::new(code, message).fatal();
        self.send(&ServerMsg::Error(e)).await
    }

    /// Sends a reply; a fatal error closes the connection after it.
    pub(crate) async fn reply(&mut self, msg: ServerMsg) -> Result<Flow, WireError> {
        let close = matches!(&msg, ServerMsg::Error(e) if e.fatal);
        self.send(&msg).await?;
        Ok(if close { Flow::Close } else { Flow::Continue })
    }

    /// Writes what the match pushed, plus whatever else is already queued, in one write.
    pub(crate) async fn push(&mut self, first: Outgoing) -> Result<(), WireError> {
        let mut next = Some(first);
        while let Some(out) = next.take() {
            match out {
                Outgoing::Observation {
                    match_id,
                    tick,
                    len,
                    obs,
                    events,
                } => {
                    if let Some(seat) = &mut self.seat {
                        seat.observed = Some(tick);
                    }
                    let msg = ObservationRef {
                        match_id,
                        tick,
                        observations: &obs[..len as usize],
                        events: &events,
                    };
                    self.conn.queue(&msg)?;
                }
                Outgoing::Error(e) => self.conn.queue(&ServerMsg::Error(e))?,
                Outgoing::MatchEnd(mut end) => {
                    if end.reason == EndReason::Ended && self.minor < 2 {
                        // 1.0 and 1.1 know no `ended`: the nearest they know
                        // is a match stopped before its clock ran out.
                        end.reason = EndReason::Shutdown;
                    }
                    self.conn.queue(&ServerMsg::MatchEnd(end))?;
                    self.seat = None;
                }
            }
            next = self.seat.as_mut().and_then(|s| s.out.try_recv().ok());
        }
        self.conn.flush().await
    }

    /// Pushes a message the match already queued, if any.
    pub(crate) async fn push_queued(&mut self) -> Result<(), WireError> {
        match self.seat.as_mut().and_then(|s| s.out.try_recv().ok()) {
            Some(out) => self.push(out).await,
            None => Ok(()),
        }
    }
}

// Observations are inline in `Outgoing` so a tick allocates nothing; this
// enum only carries one across a select.
#[allow(clippy::large_enum_variant)]
pub(crate) enum SeatEvent {
    Out(Option<Outgoing>),
    Kicked(ErrorMsg),
}

/// What the match sends; queued messages come before a kick. A kick sender
/// dropped without a kick (the match ended normally) is just ignored.
pub(crate) async fn recv_seat(seat: &mut Option<Seat>) -> SeatEvent {
    let Some(s) = seat else {
        return std::future::pending().await;
    };
    loop {
        tokio::select! {
            biased;
            out = s.out.recv() => return SeatEvent::Out(out),
            k = &mut s.kicked, if !s.kick_gone => {
                if let Ok(e) = k {
                    return SeatEvent::Kicked(e);
                }
            }
        }
        // Only a dropped kick sender gets here.
        s.kick_gone = true;
    }
}
