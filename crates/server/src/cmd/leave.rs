//! `leave`: gives the connection's robots up; they stand from now on.

use crate::match_msg::MatchCmd;
use crate::session::Session;
use naosoccer_proto::msg::{ErrorCode, ErrorMsg, Left, ServerMsg};

pub(crate) async fn handle(s: &mut Session) -> Result<ServerMsg, ErrorMsg> {
    let Some(seat) = s.seat.take() else {
        return Err(ErrorMsg::new(
            ErrorCode::FailedPrecondition,
            "not in a match",
        ));
    };
    let _ = seat.tx.send(MatchCmd::Leave { conn: s.id }).await;
    Ok(ServerMsg::Left(Left {
        match_id: seat.match_id,
    }))
}
