//! One handler per request kind (after mini-redis's `cmd/`). Each takes the
//! [`Session`] and its decoded request and returns the reply, or the error
//! to answer with; [`dispatch`] pairs the error with the request.

mod action;
mod create_match;
mod end_match;
mod hello;
mod join;
mod leave;
mod list_matches;
mod ping;
mod set_state;

use crate::config::token_eq;
use crate::match_msg::MatchCmd;
use crate::session::{Flow, Session};
use naosoccer_proto::framed::WireError;
use naosoccer_proto::msg::{ClientMsg, ErrorCode, ErrorMsg, MatchId, Undecodable};
use tokio::sync::oneshot;

/// An admin request to match `id`'s task: refused without the admin token
/// (`request` names it in the error), `not_found` for a match the server
/// does not know, `failed_precondition` once the match has finished;
/// otherwise `cmd` (built around the reply channel) goes to the match and
/// its answer comes back.
pub(crate) async fn ask_match<T>(
    s: &Session,
    request: &str,
    token: &str,
    id: MatchId,
    cmd: impl FnOnce(oneshot::Sender<T>) -> MatchCmd,
) -> Result<T, ErrorMsg> {
    if !token_eq(token, &s.shared.tokens.admin) {
        return Err(ErrorMsg::new(
            ErrorCode::PermissionDenied,
            format!("{request} needs the admin token"),
        ));
    }
    let tx = s.shared.running_match(id)?;
    let finished = || {
        ErrorMsg::new(
            ErrorCode::FailedPrecondition,
            format!("match {id} has finished"),
        )
    };
    let (reply_tx, reply_rx) = oneshot::channel();
    tx.send(cmd(reply_tx)).await.map_err(|_| finished())?;
    reply_rx.await.map_err(|_| finished())
}

/// Answers one request, in order.
pub(crate) async fn dispatch(
    s: &mut Session,
    msg: Result<ClientMsg, Undecodable>,
) -> Result<Flow, WireError> {
    let msg = match msg {
        Ok(m) => m,
        // Carries the frame's type and an action's tick when they could
        // be read, so the client can pair it (docs/PROTOCOL.md section 3).
        Err(e) => return s.reply(e.to_error().into()).await,
    };
    let kind = msg.kind();
    if !s.greeted && !matches!(msg, ClientMsg::Hello(_)) {
        let err = ErrorMsg::new(
            ErrorCode::FailedPrecondition,
            "the first message must be hello",
        )
        .fatal();
        return s.reply(err.in_reply_to(kind).into()).await;
    }
    let result = match msg {
        ClientMsg::Hello(h) => hello::handle(s, h),
        ClientMsg::CreateMatch(req) => create_match::handle(s, req),
        ClientMsg::ListMatches(_) => list_matches::handle(s),
        ClientMsg::Join(j) => join::handle(s, j).await,
        // An accepted action has no reply: the next observation answers it.
        ClientMsg::Action(a) => match action::handle(s, a).await {
            Ok(()) => return Ok(Flow::Continue),
            Err(e) => Err(e),
        },
        ClientMsg::Leave(_) => leave::handle(s).await,
        ClientMsg::Ping(p) => ping::handle(p),
        ClientMsg::EndMatch(req) => {
            let result = end_match::handle(s, req).await;
            // Its clients' match_end went out first; if this connection
            // played in the match, its own comes before the reply.
            s.push_queued().await?;
            result
        }
        ClientMsg::SetState(req) => set_state::handle(s, req).await,
        ClientMsg::Unknown => Err(ErrorMsg::new(
            ErrorCode::Unimplemented,
            "unknown message type; see docs/PROTOCOL.md for the list",
        )),
    };
    match result {
        Ok(reply) => s.reply(reply).await,
        Err(e) => {
            let e = if e.in_reply_to.is_none() {
                e.in_reply_to(kind)
            } else {
                e
            };
            s.reply(e.into()).await
        }
    }
}
