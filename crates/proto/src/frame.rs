//! Framing: every message is a 4-byte big-endian payload length followed by
//! that many bytes of UTF-8 JSON (one object with a `type` field).
//!
//! This module is IO-free so the server, the client and tests share one
//! implementation: [`FrameDecoder::decode`] looks for a complete frame in a
//! byte buffer and checks the announced length against the cap *before*
//! anything is allocated for it; [`encode_into`] appends a frame to a reused
//! buffer.

use serde::Serialize;

/// Bytes in the length prefix.
pub const HEADER_LEN: usize = 4;

/// Default cap on a frame's payload. A team observation is about 2 KiB, so
/// this leaves ample room while bounding what one peer can make us buffer.
pub const DEFAULT_MAX_FRAME: usize = 64 * 1024;

/// Framing errors. After one of these the byte stream cannot be trusted, so
/// the connection is closed (after telling the peer why, where possible).
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum FrameError {
    #[error("frame of {len} bytes exceeds the {max}-byte cap")]
    TooLarge { len: usize, max: usize },
    #[error("empty frame (length 0)")]
    Empty,
    #[error("could not encode message: {0}")]
    Encode(#[from] serde_json::Error),
}

/// Finds frames in a byte buffer.
#[derive(Debug, Clone, Copy)]
pub struct FrameDecoder {
    max_frame: usize,
}

impl Default for FrameDecoder {
    fn default() -> Self {
        FrameDecoder::new(DEFAULT_MAX_FRAME)
    }
}

/// Where a complete frame lies in the buffer passed to [`FrameDecoder::decode`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FrameSpan {
    /// Payload start (always [`HEADER_LEN`]).
    pub start: usize,
    /// Payload end; also the number of bytes the frame occupies.
    pub end: usize,
}

impl FrameDecoder {
    pub fn new(max_frame: usize) -> FrameDecoder {
        FrameDecoder { max_frame }
    }

    pub fn max_frame(&self) -> usize {
        self.max_frame
    }

    /// The announced payload length of the frame at the start of `buf`,
    /// validated against the cap; `None` if the header is not complete yet.
    pub fn announced_len(&self, buf: &[u8]) -> Result<Option<usize>, FrameError> {
        let Some(header) = buf.get(..HEADER_LEN) else {
            return Ok(None);
        };
        let len = u32::from_be_bytes([header[0], header[1], header[2], header[3]]) as usize;
        if len > self.max_frame {
            return Err(FrameError::TooLarge {
                len,
                max: self.max_frame,
            });
        }
        if len == 0 {
            return Err(FrameError::Empty);
        }
        Ok(Some(len))
    }

    /// The complete frame at the start of `buf`, if there is one. The caller
    /// parses `buf[span.start..span.end]` and then discards `span.end` bytes.
    pub fn decode(&self, buf: &[u8]) -> Result<Option<FrameSpan>, FrameError> {
        let Some(len) = self.announced_len(buf)? else {
            return Ok(None);
        };
        let end = HEADER_LEN + len;
        Ok((buf.len() >= end).then_some(FrameSpan {
            start: HEADER_LEN,
            end,
        }))
    }
}

/// Appends one frame carrying `msg` as JSON to `out` (which is not cleared, so
/// several frames can be batched into one write). Fails without touching
/// `out` if the payload would exceed `max_frame`.
pub fn encode_into<T: Serialize + ?Sized>(
    msg: &T,
    out: &mut Vec<u8>,
    max_frame: usize,
) -> Result<(), FrameError> {
    let at = out.len();
    out.extend_from_slice(&[0; HEADER_LEN]);
    if let Err(e) = serde_json::to_writer(&mut *out, msg) {
        out.truncate(at);
        return Err(e.into());
    }
    let len = out.len() - at - HEADER_LEN;
    if len > max_frame || len > u32::MAX as usize {
        out.truncate(at);
        return Err(FrameError::TooLarge {
            len,
            max: max_frame,
        });
    }
    out[at..at + HEADER_LEN].copy_from_slice(&(len as u32).to_be_bytes());
    Ok(())
}

/// One frame carrying `msg`, in a new buffer (for tests and one-off messages).
pub fn encode<T: Serialize + ?Sized>(msg: &T) -> Result<Vec<u8>, FrameError> {
    let mut out = Vec::new();
    encode_into(msg, &mut out, usize::MAX)?;
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ping_frame_bytes() {
        let bytes = encode(&serde_json::json!({"type": "ping"})).unwrap();
        assert_eq!(&bytes[..4], &[0, 0, 0, 15]);
        assert_eq!(&bytes[4..], br#"{"type":"ping"}"#);
    }

    #[test]
    fn partial_frames_wait_for_more() {
        let bytes = encode(&serde_json::json!({"type": "ping"})).unwrap();
        let dec = FrameDecoder::default();
        for cut in 0..bytes.len() {
            assert_eq!(dec.decode(&bytes[..cut]).unwrap(), None, "cut at {cut}");
        }
        assert_eq!(
            dec.decode(&bytes).unwrap(),
            Some(FrameSpan { start: 4, end: 19 })
        );
    }

    #[test]
    fn cap_checked_from_header_alone() {
        let dec = FrameDecoder::new(1024);
        let header = 1025u32.to_be_bytes();
        assert!(matches!(
            dec.decode(&header),
            Err(FrameError::TooLarge {
                len: 1025,
                max: 1024
            })
        ));
        assert!(matches!(dec.decode(&[0, 0, 0, 0]), Err(FrameError::Empty)));
        assert_eq!(dec.decode(&1024u32.to_be_bytes()).unwrap(), None);
    }

    #[test]
    fn encode_respects_cap_and_appends() {
        let mut out = vec![9u8];
        let big = "x".repeat(100);
        assert!(matches!(
            encode_into(&big, &mut out, 50),
            Err(FrameError::TooLarge { .. })
        ));
        assert_eq!(out, vec![9u8]);
        encode_into(&"ab", &mut out, 50).unwrap();
        assert_eq!(out, [9, 0, 0, 0, 4, b'"', b'a', b'b', b'"']);
    }
}
