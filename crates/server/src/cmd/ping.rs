//! `ping`: `pong` with the same nonce (keeps a lobby connection alive).

use naosoccer_proto::msg::{ErrorMsg, Ping, Pong, ServerMsg};

pub(crate) fn handle(p: Ping) -> Result<ServerMsg, ErrorMsg> {
    Ok(ServerMsg::Pong(Pong { nonce: p.nonce }))
}
