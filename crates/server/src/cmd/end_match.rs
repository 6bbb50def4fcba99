//! `end_match` (admin, protocol 1.2): ends a match now; its clients get
//! their `match_end` before this reply.

use crate::config::token_eq;
use crate::match_msg::MatchCmd;
use crate::session::Session;
use naosoccer_proto::msg::{EndMatch, ErrorCode, ErrorMsg, MatchEnded, ServerMsg};
use tokio::sync::oneshot;

pub(crate) async fn handle(s: &mut Session, req: EndMatch) -> Result<ServerMsg, ErrorMsg> {
    if !token_eq(&req.token, &s.shared.tokens.admin) {
        return Err(ErrorMsg::new(
            ErrorCode::PermissionDenied,
            "end_match needs the admin token",
        ));
    }
    let id = req.match_id;
    let tx = s.shared.running_match(id)?;
    let finished = || {
        ErrorMsg::new(
            ErrorCode::FailedPrecondition,
            format!("match {id} has finished"),
        )
    };
    let (reply_tx, reply_rx) = oneshot::channel();
    tx.send(MatchCmd::End { reply: reply_tx })
        .await
        .map_err(|_| finished())?;
    let info = reply_rx.await.map_err(|_| finished())?;
    Ok(ServerMsg::MatchEnded(MatchEnded { info }))
}
