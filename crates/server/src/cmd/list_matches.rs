//! `list_matches`: every match the server still remembers.

use crate::session::Session;
use naosoccer_proto::msg::{ErrorMsg, MatchList, ServerMsg};

pub(crate) fn handle(s: &Session) -> Result<ServerMsg, ErrorMsg> {
    Ok(ServerMsg::MatchList(MatchList {
        matches: s.shared.list_matches(),
    }))
}
