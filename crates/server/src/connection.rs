//! One TCP connection as frames, and nothing else (after mini-redis's
//! `Connection`): whole frame payloads in, encoded messages out, with the
//! write deadline and the byte counts the partial-frame deadline needs.
//! What the frames mean is the session's business.

use crate::limits::Counting;
use naosoccer_proto::frame::HEADER_LEN;
use naosoccer_proto::framed::{FrameReader, FrameWriter, WireError};
use serde::Serialize;
use std::time::Duration;
use tokio::net::tcp::{OwnedReadHalf, OwnedWriteHalf};
use tokio::net::TcpStream;

pub(crate) struct Connection {
    reader: FrameReader<Counting<OwnedReadHalf>>,
    writer: FrameWriter<OwnedWriteHalf>,
    write_timeout: Duration,
    /// Bytes of the complete frames handed out so far.
    consumed: u64,
}

impl Connection {
    pub(crate) fn new(stream: TcpStream, max_frame: usize, write_timeout: Duration) -> Connection {
        let _ = stream.set_nodelay(true);
        let (r, w) = stream.into_split();
        Connection {
            reader: FrameReader::new(Counting::new(r), max_frame),
            writer: FrameWriter::new(w, max_frame),
            write_timeout,
            consumed: 0,
        }
    }

    /// The next frame's payload; `None` when the peer closed cleanly at a
    /// frame boundary, an error when it closed mid-frame or broke the cap.
    /// Cancel-safe, so it can sit in a `select!`.
    pub(crate) async fn read_frame(&mut self) -> Result<Option<&[u8]>, WireError> {
        let frame = self.reader.read_frame().await?;
        if let Some(f) = &frame {
            self.consumed += (f.len() + HEADER_LEN) as u64;
        }
        Ok(frame)
    }

    /// Bytes read beyond the last complete frame: a frame under way.
    pub(crate) fn partial_bytes(&self) -> u64 {
        self.reader.get_ref().read() - self.consumed
    }

    /// Bytes of the complete frames read so far.
    pub(crate) fn consumed(&self) -> u64 {
        self.consumed
    }

    /// Encodes a message for the next [`flush`](Self::flush).
    pub(crate) fn queue<T: Serialize + ?Sized>(&mut self, msg: &T) -> Result<(), WireError> {
        self.writer.queue(msg)
    }

    /// Writes what is queued; a peer that does not take it within
    /// `write_timeout_ms` is given up on.
    pub(crate) async fn flush(&mut self) -> Result<(), WireError> {
        match tokio::time::timeout(self.write_timeout, self.writer.flush()).await {
            Ok(r) => r,
            Err(_) => Err(WireError::Io(std::io::Error::new(
                std::io::ErrorKind::TimedOut,
                "peer did not read within write_timeout_ms",
            ))),
        }
    }

    /// Writes one message.
    pub(crate) async fn send<T: Serialize + ?Sized>(&mut self, msg: &T) -> Result<(), WireError> {
        self.queue(msg)?;
        self.flush().await
    }

    /// Flushes and closes the write half, within the write deadline.
    pub(crate) async fn shutdown(&mut self) {
        let _ = tokio::time::timeout(self.write_timeout, self.writer.shutdown()).await;
    }
}
