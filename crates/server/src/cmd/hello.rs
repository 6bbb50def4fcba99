//! `hello`: the handshake; the first message of every connection.

use crate::session::Session;
use naosoccer_proto::msg::{
    ErrorCode, ErrorMsg, Hello, ServerMsg, Welcome, PROTOCOL_NAME, PROTOCOL_VERSION,
};

pub(crate) fn handle(s: &mut Session, h: Hello) -> Result<ServerMsg, ErrorMsg> {
    if s.greeted {
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
    s.greeted = true;
    s.minor = h.version.minor;
    tracing::debug!(conn = s.id, peer = %s.peer, client = ?h.client, version = %h.version, "hello");
    Ok(ServerMsg::Welcome(Welcome {
        protocol: PROTOCOL_NAME.into(),
        version: PROTOCOL_VERSION,
        server: concat!("naosoccer-server ", env!("CARGO_PKG_VERSION")).into(),
        max_frame: s.shared.config.max_frame.min(u32::MAX as usize) as u32,
    }))
}
