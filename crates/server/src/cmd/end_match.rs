//! `end_match` (admin, protocol 1.2): ends a match now; its clients get
//! their `match_end` before this reply.

use super::ask_match;
use crate::match_msg::MatchCmd;
use crate::session::Session;
use naosoccer_proto::msg::{EndMatch, ErrorMsg, MatchEnded, ServerMsg};

pub(crate) async fn handle(s: &mut Session, req: EndMatch) -> Result<ServerMsg, ErrorMsg> {
    let info = ask_match(s, "end_match", &req.token, req.match_id, |reply| {
        MatchCmd::End { reply }
    })
    .await?;
    Ok(ServerMsg::MatchEnded(MatchEnded { info }))
}
