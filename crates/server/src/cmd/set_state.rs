//! `set_state` (admin, protocol 1.5): moves the ball and robots of a match
//! between two ticks, as rcssserver's trainer does; the reply names the
//! tick played next, from the new state.

use super::ask_match;
use crate::match_msg::MatchCmd;
use crate::session::Session;
use naosoccer_proto::msg::{ErrorMsg, ServerMsg, SetState, StateSet};

pub(crate) async fn handle(s: &mut Session, req: SetState) -> Result<ServerMsg, ErrorMsg> {
    let id = req.match_id;
    let change = req.change();
    let tick = ask_match(s, "set_state", &req.token, id, |reply| MatchCmd::SetState {
        change,
        reply,
    })
    .await??;
    Ok(ServerMsg::StateSet(StateSet { match_id: id, tick }))
}
