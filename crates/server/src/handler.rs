//! The task behind each client connection: reads frames, answers requests in
//! order, forwards actions to its match task and writes what the match
//! pushes, until the peer leaves, breaks a limit or the server shuts down.
//!
//! Errors in a message (bad JSON, unknown type, wrong token, ...) are answered
//! with an `error` and the connection stays open; only a broken frame stream
//! (a frame over the cap, a truncated frame) or a failed handshake closes it.

use crate::cmd;
use crate::connection::Connection;
use crate::limits::{Admit, Bucket};
use crate::match_msg::{ConnId, MatchCmd};
use crate::session::{recv_seat, Flow, SeatEvent, Session};
use crate::shared::Shared;
use naosoccer_proto::frame::FrameError;
use naosoccer_proto::framed::WireError;
use naosoccer_proto::msg::{ClientMsg, ErrorCode, ErrorMsg, FrameHead, ServerMsg, Undecodable};
use std::net::SocketAddr;
use std::sync::Arc;
use std::time::Duration;
use tokio::net::TcpStream;
use tokio::time::Instant;

pub(crate) async fn serve(stream: TcpStream, peer: SocketAddr, id: ConnId, shared: Arc<Shared>) {
    let limits = &shared.config.limits;
    let bucket = Bucket::new(limits.messages_per_second, limits.message_burst);
    let write_timeout = Duration::from_millis(limits.write_timeout_ms);
    let conn = Connection::new(stream, shared.config.max_frame, write_timeout);
    let mut session = Session {
        id,
        peer,
        shared,
        conn,
        greeted: false,
        minor: 0,
        seat: None,
        joins: 0,
        bucket,
    };
    tracing::debug!(conn = id, %peer, "connected");
    match run(&mut session).await {
        Ok(()) => tracing::debug!(conn = id, %peer, "closed"),
        Err(e) => tracing::info!(conn = id, %peer, error = %e, "connection ended"),
    }
    if let Some(seat) = session.seat.take() {
        let _ = seat.tx.send(MatchCmd::Leave { conn: id }).await;
    }
    session.conn.shutdown().await;
}

/// A frame as the read loop hands it on: no longer borrowing the reader.
enum Incoming {
    Closed,
    Broken(WireError),
    Request(Result<ClientMsg, Undecodable>),
    /// Over the message rate: answer with this, and close if it is fatal.
    Refused(ErrorMsg),
}

async fn run(s: &mut Session) -> Result<(), WireError> {
    let limits = s.shared.config.limits.clone();
    let mut shutdown = s.shared.shutdown_signal();
    let mut stopping = *shutdown.borrow();
    let hello_deadline = tokio::time::sleep(Duration::from_millis(limits.hello_timeout_ms));
    tokio::pin!(hello_deadline);
    let idle_timeout = Duration::from_millis(limits.idle_timeout_ms);
    let idle = tokio::time::sleep(idle_timeout);
    tokio::pin!(idle);
    let frame_timeout = Duration::from_millis(limits.frame_timeout_ms);
    let mut frame_check = tokio::time::interval_at(Instant::now() + frame_timeout, frame_timeout);
    frame_check.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Delay);
    // `consumed` at the previous check if a partial frame was pending then.
    let mut partial_at: Option<u64> = None;
    loop {
        if stopping && s.seat.is_none() {
            let e = ErrorMsg::new(ErrorCode::Unavailable, "the server is shutting down").fatal();
            s.send(&ServerMsg::Error(e)).await?;
            return Ok(());
        }
        tokio::select! {
            biased;
            changed = shutdown.changed(), if !stopping => {
                // In a match, keep going until its match_end arrives.
                stopping = changed.is_err() || *shutdown.borrow();
            }
            _ = &mut hello_deadline, if !s.greeted => {
                let m = format!("no hello within {} ms (hello_timeout_ms)", limits.hello_timeout_ms);
                return s.fatal(ErrorCode::DeadlineExceeded, m).await;
            }
            // Only in the lobby: a seated client may wait long for its
            // match to start, and a dead seated peer is found by the
            // write deadline and keepalive instead.
            _ = &mut idle, if s.seat.is_none() => {
                let m = format!("no message for {} ms (idle_timeout_ms); send ping to stay connected", limits.idle_timeout_ms);
                return s.fatal(ErrorCode::DeadlineExceeded, m).await;
            }
            _ = frame_check.tick() => {
                let consumed = s.conn.consumed();
                if s.conn.partial_bytes() == 0 {
                    partial_at = None;
                } else if partial_at == Some(consumed) {
                    let m = format!("a frame stayed incomplete for over {} ms (frame_timeout_ms)", limits.frame_timeout_ms);
                    return s.fatal(ErrorCode::DeadlineExceeded, m).await;
                } else {
                    partial_at = Some(consumed);
                }
            }
            event = recv_seat(&mut s.seat) => {
                idle.as_mut().reset(Instant::now() + idle_timeout);
                match event {
                    SeatEvent::Kicked(e) => {
                        s.seat = None;
                        s.send(&ServerMsg::Error(e)).await?;
                        return Ok(());
                    }
                    SeatEvent::Out(Some(out)) => s.push(out).await?,
                    SeatEvent::Out(None) => {
                        // The match dropped this connection (its kick says
                        // why), or its task is gone without a match_end.
                        if let Some(mut seat) = s.seat.take() {
                            if let Ok(e) = seat.kicked.try_recv() {
                                s.send(&ServerMsg::Error(e)).await?;
                                return Ok(());
                            }
                            let m = format!("match {} ended unexpectedly", seat.match_id);
                            let e = ErrorMsg::new(ErrorCode::Internal, m).in_reply_to("action");
                            s.send(&ServerMsg::Error(e)).await?;
                        }
                    }
                }
            }
            frame = s.conn.read_frame(), if !stopping => {
                let incoming = match frame {
                    Ok(Some(f)) => admit(&mut s.bucket, f, limits.messages_per_second),
                    Ok(None) => Incoming::Closed,
                    Err(e) => Incoming::Broken(e),
                };
                if matches!(incoming, Incoming::Request(_) | Incoming::Refused(_)) {
                    idle.as_mut().reset(Instant::now() + idle_timeout);
                }
                match incoming {
                    Incoming::Closed => return Ok(()),
                    Incoming::Broken(e) => return broken(s, e).await,
                    Incoming::Refused(e) => {
                        let fatal = e.fatal;
                        s.send(&ServerMsg::Error(e)).await?;
                        if fatal {
                            return Ok(());
                        }
                    }
                    Incoming::Request(msg) => {
                        if let Flow::Close = cmd::dispatch(s, msg).await? {
                            return Ok(());
                        }
                    }
                }
            }
        }
    }
}

/// Rates a complete frame and decodes it.
fn admit(bucket: &mut Bucket, frame: &[u8], rate: u32) -> Incoming {
    match bucket.admit() {
        Admit::Yes => Incoming::Request(ClientMsg::decode(frame)),
        Admit::Refuse => {
            // Answered like any frame: pairable by its type.
            let m =
                format!("over {rate} messages per second (messages_per_second); message dropped");
            Incoming::Refused(FrameHead::peek(frame).error(ErrorCode::ResourceExhausted, m))
        }
        Admit::Disconnect => {
            let m = format!("kept sending over {rate} messages per second while refused; closing the connection");
            Incoming::Refused(
                FrameHead::peek(frame)
                    .error(ErrorCode::ResourceExhausted, m)
                    .fatal(),
            )
        }
    }
}

/// A frame stream that cannot go on: the peer hears why when it can.
async fn broken(s: &mut Session, e: WireError) -> Result<(), WireError> {
    if let WireError::Frame(e @ (FrameError::TooLarge { .. } | FrameError::Empty)) = e {
        let code = match e {
            FrameError::TooLarge { .. } => ErrorCode::ResourceExhausted,
            _ => ErrorCode::InvalidArgument,
        };
        let err = ErrorMsg::new(code, format!("{e}; closing the connection")).fatal();
        s.send(&ServerMsg::Error(err)).await?;
        return Err(WireError::Frame(e));
    }
    Err(e)
}
