//! The server's input path without the sockets: the frame decoder over an
//! arbitrary byte stream, then every complete payload through the message
//! parser (client and server messages). Nothing may panic; the decoder must
//! never hand out a span beyond the buffer or over the cap, and a message
//! that parses must survive a round trip.
#![no_main]

use libfuzzer_sys::fuzz_target;
use naosoccer_proto::frame::{FrameDecoder, HEADER_LEN};
use naosoccer_proto::msg::{ClientMsg, ServerMsg};

/// Small, so the cap check is reached often.
const MAX_FRAME: usize = 4096;

fuzz_target!(|data: &[u8]| {
    let dec = FrameDecoder::new(MAX_FRAME);
    let mut at = 0;
    while let Ok(Some(span)) = dec.decode(&data[at..]) {
        assert_eq!(span.start, HEADER_LEN);
        assert!(span.end <= data.len() - at);
        assert!(span.end - span.start <= MAX_FRAME);
        assert!(span.end > span.start, "empty frames are errors");
        let payload = &data[at + span.start..at + span.end];
        // `Unknown` (any other `type`) is receive-only by design.
        if let Ok(msg) = serde_json::from_slice::<ClientMsg>(payload)
            .map_err(drop)
            .and_then(|m| {
                if m == ClientMsg::Unknown {
                    Err(())
                } else {
                    Ok(m)
                }
            })
        {
            let again = serde_json::to_vec(&msg).expect("a parsed message encodes");
            let back: ClientMsg = serde_json::from_slice(&again).expect("and parses again");
            assert_eq!(back, msg);
        }
        let _ = serde_json::from_slice::<ServerMsg>(payload);
        at += span.end;
    }
});
