//! Frames over tokio byte streams (feature `tokio`), shared by the server
//! and the client library: [`FrameReader`] yields whole frame payloads,
//! [`FrameWriter`] encodes messages into a reused buffer. The size checks
//! are [`crate::frame`]'s; this adds only the reads and writes.

use crate::frame::{self, FrameDecoder, FrameError, HEADER_LEN};
use serde::Serialize;
use std::io;
use tokio::io::{AsyncRead, AsyncReadExt, AsyncWrite, AsyncWriteExt};

/// Reading or writing frames failed; the stream is unusable afterwards.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum WireError {
    #[error("i/o error: {0}")]
    Io(#[from] io::Error),
    #[error(transparent)]
    Frame(#[from] FrameError),
    #[error("peer closed the connection in the middle of a frame")]
    TruncatedFrame,
}

/// Reads frames from `R`. Cancel-safe: dropping a pending
/// [`read_frame`](FrameReader::read_frame) future loses no bytes, so it can
/// sit in a `tokio::select!`.
#[derive(Debug)]
pub struct FrameReader<R> {
    io: R,
    buf: Vec<u8>,
    /// Start of unread bytes in `buf`.
    start: usize,
    /// Bytes of the frame handed out last time, dropped on the next call.
    consumed: usize,
    decoder: FrameDecoder,
}

impl<R: AsyncRead + Unpin> FrameReader<R> {
    pub fn new(io: R, max_frame: usize) -> FrameReader<R> {
        FrameReader {
            io,
            buf: Vec::with_capacity(4096),
            start: 0,
            consumed: 0,
            decoder: FrameDecoder::new(max_frame),
        }
    }

    /// The next frame's payload; `None` when the peer closed the stream
    /// cleanly at a frame boundary. The announced length is checked against
    /// the cap before any room is made for the payload.
    pub async fn read_frame(&mut self) -> Result<Option<&[u8]>, WireError> {
        self.start += std::mem::take(&mut self.consumed);
        loop {
            let pending = &self.buf[self.start..];
            if let Some(span) = self.decoder.decode(pending)? {
                self.consumed = span.end;
                let at = self.start;
                return Ok(Some(&self.buf[at + span.start..at + span.end]));
            }
            // Compact so the buffer never holds more than one partial frame
            // plus one read's worth of bytes.
            if self.start > 0 {
                self.buf.drain(..self.start);
                self.start = 0;
            }
            let want = match self.decoder.announced_len(&self.buf)? {
                Some(len) => HEADER_LEN + len - self.buf.len(),
                None => 4096,
            };
            self.buf.reserve(want.max(1024));
            if self.io.read_buf(&mut self.buf).await? == 0 {
                return if self.buf.is_empty() {
                    Ok(None)
                } else {
                    Err(WireError::TruncatedFrame)
                };
            }
        }
    }

    pub fn get_ref(&self) -> &R {
        &self.io
    }
}

/// Writes frames to `W` through one reused encode buffer. `queue` several
/// messages and `flush` them in one write, or `send` one.
#[derive(Debug)]
pub struct FrameWriter<W> {
    io: W,
    buf: Vec<u8>,
    max_frame: usize,
}

impl<W: AsyncWrite + Unpin> FrameWriter<W> {
    pub fn new(io: W, max_frame: usize) -> FrameWriter<W> {
        FrameWriter {
            io,
            buf: Vec::with_capacity(4096),
            max_frame,
        }
    }

    /// Encodes `msg` into the pending buffer.
    pub fn queue<T: Serialize + ?Sized>(&mut self, msg: &T) -> Result<(), WireError> {
        frame::encode_into(msg, &mut self.buf, self.max_frame)?;
        Ok(())
    }

    /// Queues raw bytes (tests use this to send malformed frames).
    pub fn queue_raw(&mut self, bytes: &[u8]) {
        self.buf.extend_from_slice(bytes);
    }

    /// Writes everything queued.
    pub async fn flush(&mut self) -> Result<(), WireError> {
        if !self.buf.is_empty() {
            self.io.write_all(&self.buf).await?;
            self.buf.clear();
        }
        Ok(())
    }

    pub async fn send<T: Serialize + ?Sized>(&mut self, msg: &T) -> Result<(), WireError> {
        self.queue(msg)?;
        self.flush().await
    }

    pub async fn shutdown(&mut self) -> Result<(), WireError> {
        self.flush().await?;
        self.io.shutdown().await?;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[tokio::test]
    async fn frames_across_odd_reads() {
        let (a, b) = tokio::io::duplex(7);
        let mut w = FrameWriter::new(a, 1024);
        let writer = tokio::spawn(async move {
            for i in 0..50u32 {
                w.queue(&serde_json::json!({"type": "ping", "nonce": i}))
                    .unwrap();
            }
            w.shutdown().await.unwrap();
        });
        let mut r = FrameReader::new(b, 1024);
        for i in 0..50u64 {
            let f = r.read_frame().await.unwrap().unwrap();
            let v: serde_json::Value = serde_json::from_slice(f).unwrap();
            assert_eq!(v["nonce"], i);
        }
        assert!(r.read_frame().await.unwrap().is_none());
        writer.await.unwrap();
    }

    #[tokio::test]
    async fn truncated_and_oversized() {
        let (mut a, b) = tokio::io::duplex(64);
        a.write_all(&[0, 0, 0, 10, b'{']).await.unwrap();
        drop(a);
        let mut r = FrameReader::new(b, 1024);
        assert!(matches!(
            r.read_frame().await,
            Err(WireError::TruncatedFrame)
        ));

        let (mut a, b) = tokio::io::duplex(64);
        a.write_all(&[0, 1, 0, 0]).await.unwrap();
        let mut r = FrameReader::new(b, 1024);
        assert!(matches!(
            r.read_frame().await,
            Err(WireError::Frame(FrameError::TooLarge { len: 65536, .. }))
        ));
    }
}
