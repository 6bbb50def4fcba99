//! One client connection: reads frames, answers requests in order, forwards
//! actions to its match task and writes what the match pushes.
//!
//! Errors in a message (bad JSON, unknown type, wrong token, ...) are answered
//! with an `error` and the connection stays open; only a broken frame stream
//! (a frame over the cap, a truncated frame) or a failed handshake closes it.

use crate::match_task::{ConnId, MatchCmd, Outgoing};
use crate::server::Shared;
use naosoccer_client::framed::{FrameReader, FrameWriter, WireError};
use naosoccer_proto::frame::FrameError;
use naosoccer_proto::msg::{
    ActionMsg, ClientMsg, EndMatch, EndReason, ErrorCode, ErrorMsg, FrameHead, Hello, Join, Left,
    MatchCreated, MatchEnded, MatchId, MatchList, ObservationRef, Player, Pong, ServerMsg,
    Undecodable, Welcome, PROTOCOL_NAME, PROTOCOL_VERSION,
};
use naosoccer_proto::{Action, Team, PLAYERS_PER_TEAM};
use std::net::SocketAddr;
use std::pin::Pin;
use std::sync::Arc;
use std::task::{Context, Poll};
use std::time::Duration;
use tokio::io::{AsyncRead, ReadBuf};
use tokio::net::tcp::{OwnedReadHalf, OwnedWriteHalf};
use tokio::net::TcpStream;
use tokio::sync::{mpsc, oneshot};
use tokio::time::Instant;

/// The read half, counting bytes so the connection can tell a frame that
/// stalled half-way (bytes read beyond the last complete frame) from silence.
struct Counting {
    inner: OwnedReadHalf,
    read: u64,
}

impl AsyncRead for Counting {
    fn poll_read(
        mut self: Pin<&mut Self>,
        cx: &mut Context<'_>,
        buf: &mut ReadBuf<'_>,
    ) -> Poll<std::io::Result<()>> {
        let before = buf.filled().len();
        let r = Pin::new(&mut self.inner).poll_read(cx, buf);
        self.read += (buf.filled().len() - before) as u64;
        r
    }
}

/// Messages per second per connection: a token bucket on tokio's clock
/// (wall-clock time is fine here, at the server's edge; it never reaches a
/// match's state).
struct Bucket {
    tokens: f64,
    rate: f64,
    burst: f64,
    last: Instant,
}

enum Admit {
    Yes,
    /// Over the rate: refuse this message, keep the connection.
    Refuse,
    /// Still sending a whole burst beyond the rate while refused: disconnect.
    Disconnect,
}

impl Bucket {
    fn new(rate: u32, burst: u32) -> Bucket {
        Bucket {
            tokens: f64::from(burst),
            rate: f64::from(rate),
            burst: f64::from(burst),
            last: Instant::now(),
        }
    }

    fn admit(&mut self) -> Admit {
        let now = Instant::now();
        let dt = now.saturating_duration_since(self.last).as_secs_f64();
        self.last = now;
        self.tokens = (self.tokens + dt * self.rate).min(self.burst);
        self.tokens -= 1.0;
        if self.tokens >= 0.0 {
            Admit::Yes
        } else if self.tokens >= -self.burst {
            Admit::Refuse
        } else {
            Admit::Disconnect
        }
    }
}

/// The connection's seat in a match.
struct Seat {
    match_id: MatchId,
    team: Team,
    players: Vec<Player>,
    tx: mpsc::Sender<MatchCmd>,
    out: mpsc::Receiver<Outgoing>,
    /// Fires if the match dropped this connection (its queue was full).
    kicked: oneshot::Receiver<ErrorMsg>,
    kick_gone: bool,
    /// The newest tick observed; actions may not name a later one.
    observed: Option<u64>,
}

struct Conn {
    id: ConnId,
    peer: SocketAddr,
    shared: Arc<Shared>,
    writer: FrameWriter<OwnedWriteHalf>,
    greeted: bool,
    /// The minor protocol version the client said in its `hello`.
    minor: u32,
    seat: Option<Seat>,
    joins: u32,
    bucket: Bucket,
    write_timeout: Duration,
    /// Bytes of complete frames handed to `request` (see [`Counting`]).
    consumed: u64,
}

enum Flow {
    Continue,
    Close,
}

pub(crate) async fn serve(stream: TcpStream, peer: SocketAddr, id: ConnId, shared: Arc<Shared>) {
    let _ = stream.set_nodelay(true);
    let max_frame = shared.config.max_frame;
    let limits = &shared.config.limits;
    let bucket = Bucket::new(limits.messages_per_second, limits.message_burst);
    let write_timeout = Duration::from_millis(limits.write_timeout_ms);
    let (r, w) = stream.into_split();
    let mut reader = FrameReader::new(Counting { inner: r, read: 0 }, max_frame);
    let mut conn = Conn {
        id,
        peer,
        shared,
        writer: FrameWriter::new(w, max_frame),
        greeted: false,
        minor: 0,
        seat: None,
        joins: 0,
        bucket,
        write_timeout,
        consumed: 0,
    };
    tracing::debug!(conn = id, %peer, "connected");
    match conn.run(&mut reader).await {
        Ok(()) => tracing::debug!(conn = id, %peer, "closed"),
        Err(e) => tracing::info!(conn = id, %peer, error = %e, "connection ended"),
    }
    if let Some(seat) = conn.seat.take() {
        let _ = seat.tx.send(MatchCmd::Leave { conn: id }).await;
    }
    let _ = tokio::time::timeout(conn.write_timeout, conn.writer.shutdown()).await;
}

impl Conn {
    async fn run(&mut self, reader: &mut FrameReader<Counting>) -> Result<(), WireError> {
        let limits = self.shared.config.limits.clone();
        let mut shutdown = self.shared.shutdown_signal();
        let mut stopping = *shutdown.borrow();
        let hello_timeout = Duration::from_millis(limits.hello_timeout_ms);
        let hello_deadline = tokio::time::sleep(hello_timeout);
        tokio::pin!(hello_deadline);
        let idle_timeout = Duration::from_millis(limits.idle_timeout_ms);
        let idle = tokio::time::sleep(idle_timeout);
        tokio::pin!(idle);
        let frame_timeout = Duration::from_millis(limits.frame_timeout_ms);
        let mut frame_check =
            tokio::time::interval_at(Instant::now() + frame_timeout, frame_timeout);
        frame_check.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Delay);
        // `consumed` at the previous check if a partial frame was pending then.
        let mut partial_at: Option<u64> = None;
        loop {
            if stopping && self.seat.is_none() {
                let e =
                    ErrorMsg::new(ErrorCode::Unavailable, "the server is shutting down").fatal();
                self.send(&ServerMsg::Error(e)).await?;
                return Ok(());
            }
            tokio::select! {
                biased;
                changed = shutdown.changed(), if !stopping => {
                    // In a match, keep going until its match_end arrives.
                    stopping = changed.is_err() || *shutdown.borrow();
                }
                _ = &mut hello_deadline, if !self.greeted => {
                    let m = format!("no hello within {} ms (hello_timeout_ms)", limits.hello_timeout_ms);
                    return self.fatal(ErrorCode::DeadlineExceeded, m).await;
                }
                // Only in the lobby: a seated client may wait long for its
                // match to start, and a dead seated peer is found by the
                // write deadline and keepalive instead.
                _ = &mut idle, if self.seat.is_none() => {
                    let m = format!("no message for {} ms (idle_timeout_ms); send ping to stay connected", limits.idle_timeout_ms);
                    return self.fatal(ErrorCode::DeadlineExceeded, m).await;
                }
                _ = frame_check.tick() => {
                    let pending = reader.get_ref().read - self.consumed;
                    if pending == 0 {
                        partial_at = None;
                    } else if partial_at == Some(self.consumed) {
                        let m = format!("a frame stayed incomplete for over {} ms (frame_timeout_ms)", limits.frame_timeout_ms);
                        return self.fatal(ErrorCode::DeadlineExceeded, m).await;
                    } else {
                        partial_at = Some(self.consumed);
                    }
                }
                event = recv_seat(&mut self.seat) => {
                    idle.as_mut().reset(Instant::now() + idle_timeout);
                    match event {
                        SeatEvent::Kicked(e) => {
                            self.seat = None;
                            self.send(&ServerMsg::Error(e)).await?;
                            return Ok(());
                        }
                        SeatEvent::Out(Some(out)) => self.push(out).await?,
                        SeatEvent::Out(None) => {
                            // The match dropped this connection (its kick says
                            // why), or its task is gone without a match_end.
                            if let Some(mut seat) = self.seat.take() {
                                if let Ok(e) = seat.kicked.try_recv() {
                                    self.send(&ServerMsg::Error(e)).await?;
                                    return Ok(());
                                }
                                let m = format!("match {} ended unexpectedly", seat.match_id);
                                self.send(&ServerMsg::Error(ErrorMsg::new(ErrorCode::Internal, m))).await?;
                            }
                        }
                    }
                }
                frame = reader.read_frame(), if !stopping => {
                    let frame = match frame {
                        Ok(Some(f)) => f,
                        Ok(None) => return Ok(()),
                        Err(WireError::Frame(e @ (FrameError::TooLarge { .. } | FrameError::Empty))) => {
                            let code = match e {
                                FrameError::TooLarge { .. } => ErrorCode::ResourceExhausted,
                                _ => ErrorCode::InvalidArgument,
                            };
                            let err = ErrorMsg::new(code, format!("{e}; closing the connection")).fatal();
                            self.send(&ServerMsg::Error(err)).await?;
                            return Err(WireError::Frame(e));
                        }
                        Err(e) => return Err(e),
                    };
                    self.consumed += (frame.len() + naosoccer_proto::frame::HEADER_LEN) as u64;
                    idle.as_mut().reset(Instant::now() + idle_timeout);
                    match self.bucket.admit() {
                        Admit::Yes => {}
                        Admit::Refuse => {
                            // Answered like any frame: pairable by its type.
                            let m = format!("over {} messages per second (messages_per_second); message dropped", limits.messages_per_second);
                            let e = FrameHead::peek(frame).error(ErrorCode::ResourceExhausted, m);
                            self.send(&ServerMsg::Error(e)).await?;
                            continue;
                        }
                        Admit::Disconnect => {
                            let m = format!("kept sending over {} messages per second while refused; closing the connection", limits.messages_per_second);
                            let e = FrameHead::peek(frame).error(ErrorCode::ResourceExhausted, m).fatal();
                            return self.send(&ServerMsg::Error(e)).await;
                        }
                    }
                    let msg = ClientMsg::decode(frame);
                    if let Flow::Close = self.request(msg).await? {
                        return Ok(());
                    }
                }
            }
        }
    }

    async fn fatal(&mut self, code: ErrorCode, message: String) -> Result<(), WireError> {
        let e = ErrorMsg::new(code, message).fatal();
        self.send(&ServerMsg::Error(e)).await
    }

    /// Writes one message; a peer that does not take it within
    /// `write_timeout_ms` is given up on.
    async fn send(&mut self, msg: &ServerMsg) -> Result<(), WireError> {
        self.writer.queue(msg)?;
        self.flush().await
    }

    async fn flush(&mut self) -> Result<(), WireError> {
        match tokio::time::timeout(self.write_timeout, self.writer.flush()).await {
            Ok(r) => r,
            Err(_) => Err(WireError::Io(std::io::Error::new(
                std::io::ErrorKind::TimedOut,
                "peer did not read within write_timeout_ms",
            ))),
        }
    }

    /// Writes what the match pushed, plus whatever else is already queued, in one write.
    async fn push(&mut self, first: Outgoing) -> Result<(), WireError> {
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
                    self.writer.queue(&msg)?;
                }
                Outgoing::Error(e) => self.writer.queue(&ServerMsg::Error(e))?,
                Outgoing::MatchEnd(mut end) => {
                    if end.reason == EndReason::Ended && self.minor < 2 {
                        // 1.0 and 1.1 know no `ended`: the nearest they know
                        // is a match stopped before its clock ran out.
                        end.reason = EndReason::Shutdown;
                    }
                    self.writer.queue(&ServerMsg::MatchEnd(end))?;
                    self.seat = None;
                }
            }
            next = self.seat.as_mut().and_then(|s| s.out.try_recv().ok());
        }
        self.flush().await
    }

    async fn reply(&mut self, msg: ServerMsg) -> Result<Flow, WireError> {
        let close = matches!(&msg, ServerMsg::Error(e) if e.fatal);
        self.send(&msg).await?;
        Ok(if close { Flow::Close } else { Flow::Continue })
    }

    async fn request(&mut self, msg: Result<ClientMsg, Undecodable>) -> Result<Flow, WireError> {
        let msg = match msg {
            Ok(m) => m,
            // Carries the frame's type and an action's tick when they could
            // be read, so the client can pair it (docs/PROTOCOL.md section 3).
            Err(e) => return self.reply(e.to_error().into()).await,
        };
        let kind = msg.kind();
        if !self.greeted && !matches!(msg, ClientMsg::Hello(_)) {
            let err = ErrorMsg::new(
                ErrorCode::FailedPrecondition,
                "the first message must be hello",
            )
            .fatal();
            return self.reply(err.in_reply_to(kind).into()).await;
        }
        let result = match msg {
            ClientMsg::Hello(h) => self.hello(h),
            ClientMsg::CreateMatch(req) => {
                if !token_eq(&req.token, &self.shared.tokens.admin) {
                    Err(ErrorMsg::new(
                        ErrorCode::PermissionDenied,
                        "create_match needs the admin token",
                    ))
                } else {
                    self.shared
                        .create_match(&req)
                        .map(|info| ServerMsg::MatchCreated(MatchCreated { info }))
                }
            }
            ClientMsg::ListMatches(_) => Ok(ServerMsg::MatchList(MatchList {
                matches: self.shared.list_matches(),
            })),
            ClientMsg::Join(j) => self.join(j).await,
            ClientMsg::Action(a) => match self.action(a).await {
                Ok(()) => return Ok(Flow::Continue),
                Err(e) => Err(e),
            },
            ClientMsg::Leave(_) => match self.seat.take() {
                Some(seat) => {
                    let _ = seat.tx.send(MatchCmd::Leave { conn: self.id }).await;
                    Ok(ServerMsg::Left(Left {
                        match_id: seat.match_id,
                    }))
                }
                None => Err(ErrorMsg::new(
                    ErrorCode::FailedPrecondition,
                    "not in a match",
                )),
            },
            ClientMsg::Ping(p) => Ok(ServerMsg::Pong(Pong { nonce: p.nonce })),
            ClientMsg::EndMatch(req) => {
                let result = self.end_match(req).await;
                // Its clients' match_end went out first; if this connection
                // played in the match, its own comes before the reply.
                if let Some(out) = self.seat.as_mut().and_then(|s| s.out.try_recv().ok()) {
                    self.push(out).await?;
                }
                result
            }
            ClientMsg::Unknown => Err(ErrorMsg::new(
                ErrorCode::Unimplemented,
                "unknown message type; see docs/PROTOCOL.md for the list",
            )),
        };
        match result {
            Ok(reply) => self.reply(reply).await,
            Err(e) => {
                let e = if e.in_reply_to.is_none() {
                    e.in_reply_to(kind)
                } else {
                    e
                };
                self.reply(e.into()).await
            }
        }
    }

    fn hello(&mut self, h: Hello) -> Result<ServerMsg, ErrorMsg> {
        if self.greeted {
            return Err(ErrorMsg::new(
                ErrorCode::FailedPrecondition,
                "hello was already sent",
            ));
        }
        if h.protocol != PROTOCOL_NAME {
            let m = format!("this is a {PROTOCOL_NAME} server, not {:?}", h.protocol);
            return Err(ErrorMsg::new(ErrorCode::InvalidArgument, m).fatal());
        }
        if h.version.major != PROTOCOL_VERSION.major {
            let m = format!(
                "protocol version {} is not supported; this server speaks {}.x ({})",
                h.version, PROTOCOL_VERSION.major, PROTOCOL_VERSION
            );
            return Err(ErrorMsg::new(ErrorCode::Unimplemented, m).fatal());
        }
        self.greeted = true;
        self.minor = h.version.minor;
        tracing::debug!(conn = self.id, peer = %self.peer, client = ?h.client, version = %h.version, "hello");
        Ok(ServerMsg::Welcome(Welcome {
            protocol: PROTOCOL_NAME.into(),
            version: PROTOCOL_VERSION,
            server: concat!("naosoccer-server ", env!("CARGO_PKG_VERSION")).into(),
            max_frame: self.shared.config.max_frame.min(u32::MAX as usize) as u32,
        }))
    }

    async fn end_match(&mut self, req: EndMatch) -> Result<ServerMsg, ErrorMsg> {
        if !token_eq(&req.token, &self.shared.tokens.admin) {
            return Err(ErrorMsg::new(
                ErrorCode::PermissionDenied,
                "end_match needs the admin token",
            ));
        }
        let id = req.match_id;
        let tx = self.shared.running_match(id)?;
        let finished = || {
            ErrorMsg::new(
                ErrorCode::FailedPrecondition,
                format!("match {id} has finished"),
            )
        };
        let (reply_tx, reply_rx) = oneshot::channel();
        tx.send(MatchCmd::End { reply: reply_tx })
            .await
            .map_err(|_| finished())?;
        let info = reply_rx.await.map_err(|_| finished())?;
        Ok(ServerMsg::MatchEnded(MatchEnded { info }))
    }

    async fn join(&mut self, j: Join) -> Result<ServerMsg, ErrorMsg> {
        if !token_eq(&j.token, self.shared.tokens.team(j.team)) {
            return Err(ErrorMsg::new(
                ErrorCode::PermissionDenied,
                format!("wrong token for team {}", j.team),
            ));
        }
        if let Some(seat) = &self.seat {
            let m = format!(
                "this connection already plays in match {}; leave first",
                seat.match_id
            );
            return Err(ErrorMsg::new(ErrorCode::FailedPrecondition, m));
        }
        if j.players.is_empty() {
            return Err(ErrorMsg::new(
                ErrorCode::InvalidArgument,
                "players is empty",
            ));
        }
        let mut seen = [false; PLAYERS_PER_TEAM];
        for p in &j.players {
            if std::mem::replace(&mut seen[p.index()], true) {
                return Err(ErrorMsg::new(
                    ErrorCode::InvalidArgument,
                    format!("player {p} listed twice"),
                ));
            }
        }
        let max_joins = self.shared.config.limits.max_joins_per_connection;
        if self.joins >= max_joins {
            let m = format!("this connection already joined {max_joins} times (max_joins_per_connection); reconnect to join again");
            return Err(ErrorMsg::new(ErrorCode::ResourceExhausted, m));
        }
        let (match_id, tx) = self.shared.find_match(j.match_id, j.team, &j.players)?;
        let finished = || {
            ErrorMsg::new(
                ErrorCode::FailedPrecondition,
                format!("match {match_id} has finished"),
            )
        };
        let (out_tx, out_rx) = mpsc::channel(self.shared.config.limits.max_outbound);
        let (kick_tx, kick_rx) = oneshot::channel();
        let (reply_tx, reply_rx) = oneshot::channel();
        let cmd = MatchCmd::Join {
            conn: self.id,
            team: j.team,
            players: j.players.clone(),
            out: out_tx,
            kick: kick_tx,
            reply: reply_tx,
        };
        tx.send(cmd).await.map_err(|_| finished())?;
        let joined = reply_rx.await.map_err(|_| finished())??;
        self.joins += 1;
        self.seat = Some(Seat {
            match_id,
            team: j.team,
            players: j.players,
            tx,
            out: out_rx,
            kicked: kick_rx,
            kick_gone: false,
            observed: None,
        });
        Ok(ServerMsg::Joined(joined))
    }

    async fn action(&mut self, a: ActionMsg) -> Result<(), ErrorMsg> {
        let with_tick = |e: ErrorMsg| ErrorMsg {
            tick: Some(a.tick),
            ..e
        };
        let Some(seat) = &self.seat else {
            return Err(with_tick(ErrorMsg::new(
                ErrorCode::FailedPrecondition,
                "join a match before sending actions",
            )));
        };
        if let Some(team) = a.team {
            if team != seat.team {
                let m = format!(
                    "this connection plays for {}; it cannot act for {team}",
                    seat.team
                );
                return Err(with_tick(ErrorMsg::new(ErrorCode::PermissionDenied, m)));
            }
        }
        let mut actions: [Option<Action>; PLAYERS_PER_TEAM] = [None; PLAYERS_PER_TEAM];
        for pa in &a.actions {
            if !seat.players.contains(&pa.player) {
                let m = format!(
                    "{} player {} is not controlled by this connection",
                    seat.team, pa.player
                );
                return Err(with_tick(ErrorMsg::new(ErrorCode::PermissionDenied, m)));
            }
            if actions[pa.player.index()].replace(pa.action).is_some() {
                let m = format!("two actions for player {}", pa.player);
                return Err(with_tick(ErrorMsg::new(ErrorCode::InvalidArgument, m)));
            }
        }
        match seat.observed {
            None => {
                let m = "no observation yet: the match has not started";
                return Err(with_tick(ErrorMsg::new(ErrorCode::FailedPrecondition, m)));
            }
            Some(t) if a.tick > t => {
                let m = format!(
                    "tick {} is in the future (last observation: tick {t})",
                    a.tick
                );
                return Err(with_tick(ErrorMsg::new(ErrorCode::InvalidArgument, m)));
            }
            Some(_) => {}
        }
        // A send error means the match just ended; its match_end is on the way.
        let _ = seat
            .tx
            .send(MatchCmd::Action {
                conn: self.id,
                team: seat.team,
                tick: a.tick,
                actions,
            })
            .await;
        Ok(())
    }
}

// Observations are inline in `Outgoing` so a tick allocates nothing; this
// enum only carries one across a select.
#[allow(clippy::large_enum_variant)]
enum SeatEvent {
    Out(Option<Outgoing>),
    Kicked(ErrorMsg),
}

/// What the match sends; queued messages come before a kick. A kick sender
/// dropped without a kick (the match ended normally) is just ignored.
async fn recv_seat(seat: &mut Option<Seat>) -> SeatEvent {
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

/// Token comparison whose time does not depend on the tokens' contents
/// (`subtle`'s constant-time equality; only a length difference shows).
fn token_eq(given: &str, expected: &str) -> bool {
    use subtle::ConstantTimeEq;
    given.as_bytes().ct_eq(expected.as_bytes()).into()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn token_eq_compares_whole_tokens() {
        assert!(token_eq("blue-secret", "blue-secret"));
        assert!(!token_eq("blue-secreT", "blue-secret"));
        assert!(!token_eq("blue-secret", "blue-secret-2"));
        assert!(!token_eq("", "blue-secret"));
    }

    #[tokio::test(start_paused = true)]
    async fn bucket_refuses_over_the_rate_and_refills() {
        let mut b = Bucket::new(10, 3);
        for _ in 0..3 {
            assert!(matches!(b.admit(), Admit::Yes));
        }
        assert!(matches!(b.admit(), Admit::Refuse));
        // 0.2 s at 10/s: two tokens back, one of them owed for the refusal.
        tokio::time::advance(Duration::from_millis(200)).await;
        assert!(matches!(b.admit(), Admit::Yes));
        assert!(matches!(b.admit(), Admit::Refuse));
        assert!(matches!(b.admit(), Admit::Refuse));
        assert!(matches!(b.admit(), Admit::Refuse));
        assert!(matches!(b.admit(), Admit::Disconnect));
        // Refills never exceed the burst.
        tokio::time::advance(Duration::from_secs(3600)).await;
        for _ in 0..3 {
            assert!(matches!(b.admit(), Admit::Yes));
        }
        assert!(matches!(b.admit(), Admit::Refuse));
    }
}
