//! What one peer may cost the server, apart from the frame cap (which
//! `naosoccer_proto::frame` checks): a read half that counts its bytes, so a
//! frame that stalled half-way can be told from silence, and the message-rate
//! token bucket. The numbers come from [`crate::Limits`].

use std::pin::Pin;
use std::task::{Context, Poll};
use tokio::io::{AsyncRead, ReadBuf};
use tokio::time::Instant;

/// A read half that counts the bytes it has read.
pub(crate) struct Counting<R> {
    inner: R,
    read: u64,
}

impl<R> Counting<R> {
    pub(crate) fn new(inner: R) -> Counting<R> {
        Counting { inner, read: 0 }
    }

    /// Bytes read so far.
    pub(crate) fn read(&self) -> u64 {
        self.read
    }
}

impl<R: AsyncRead + Unpin> AsyncRead for Counting<R> {
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
pub(crate) struct Bucket {
    tokens: f64,
    rate: f64,
    burst: f64,
    last: Instant,
}

#[derive(Debug, PartialEq, Eq)]
pub(crate) enum Admit {
    Yes,
    /// Over the rate: refuse this message, keep the connection.
    Refuse,
    /// Still sending a whole burst beyond the rate while refused: disconnect.
    Disconnect,
}

impl Bucket {
    pub(crate) fn new(rate: u32, burst: u32) -> Bucket {
        Bucket {
            tokens: f64::from(burst),
            rate: f64::from(rate),
            burst: f64::from(burst),
            last: Instant::now(),
        }
    }

    pub(crate) fn admit(&mut self) -> Admit {
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

#[cfg(test)]
mod tests {
    use super::*;
    use std::time::Duration;
    use tokio::io::AsyncReadExt;

    #[tokio::test(start_paused = true)]
    async fn bucket_refuses_over_the_rate_and_refills() {
        let mut b = Bucket::new(10, 3);
        for _ in 0..3 {
            assert_eq!(b.admit(), Admit::Yes);
        }
        assert_eq!(b.admit(), Admit::Refuse);
        // 0.2 s at 10/s: two tokens back, one of them owed for the refusal.
        tokio::time::advance(Duration::from_millis(200)).await;
        assert_eq!(b.admit(), Admit::Yes);
        assert_eq!(b.admit(), Admit::Refuse);
        assert_eq!(b.admit(), Admit::Refuse);
        assert_eq!(b.admit(), Admit::Refuse);
        assert_eq!(b.admit(), Admit::Disconnect);
        // Refills never exceed the burst.
        tokio::time::advance(Duration::from_secs(3600)).await;
        for _ in 0..3 {
            assert_eq!(b.admit(), Admit::Yes);
        }
        assert_eq!(b.admit(), Admit::Refuse);
    }

    #[tokio::test]
    async fn counting_counts_every_byte_read() {
        let mut c = Counting::new(&b"hello, frames"[..]);
        let mut buf = [0u8; 5];
        c.read_exact(&mut buf).await.unwrap();
        assert_eq!(c.read(), 5);
        let mut rest = Vec::new();
        c.read_to_end(&mut rest).await.unwrap();
        assert_eq!(c.read(), 13);
    }
}
