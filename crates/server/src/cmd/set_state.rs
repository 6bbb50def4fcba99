//! `set_state` (admin, protocol 1.5): moves the ball and robots of a match
//! between two ticks, as rcssserver's trainer does; the reply names the
//! tick played next, from the new state.

use crate::config::token_eq;
use crate::match_msg::MatchCmd;
use crate::session::Session;
use naosoccer_proto::msg::{ErrorCode, ErrorMsg, ServerMsg, SetState, StateSet};
use tokio::sync::oneshot;

pub(crate) async fn handle(s: &mut Session, req: SetState) -> Result<ServerMsg, ErrorMsg> {
    if !token_eq(&req.token, &s.shared.tokens.admin) {
        return Err(ErrorMsg::new(
            ErrorCode::PermissionDenied,
            "set_state needs the admin token",
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
    let cmd = MatchCmd::SetState {
        change: req.change(),
        reply: reply_tx,
    };
    tx.send(cmd).await.map_err(|_| finished())?;
    let tick = reply_rx.await.map_err(|_| finished())??;
    Ok(ServerMsg::StateSet(StateSet { match_id: id, tick }))
}
