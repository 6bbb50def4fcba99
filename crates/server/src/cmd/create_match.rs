//! `create_match` (admin): a new match with its own task.

use crate::config::token_eq;
use crate::session::Session;
use crate::shared::CreateError;
use naosoccer_proto::msg::{CreateMatch, ErrorCode, ErrorMsg, MatchCreated, ServerMsg};

pub(crate) fn handle(s: &mut Session, req: CreateMatch) -> Result<ServerMsg, ErrorMsg> {
    if !token_eq(&req.token, &s.shared.tokens.admin) {
        return Err(ErrorMsg::new(
            ErrorCode::PermissionDenied,
            "create_match needs the admin token",
        ));
    }
    let info = s.shared.create_match(&req).map_err(|e| match e {
        CreateError::Refused(e) => e,
        CreateError::Build(e) => ErrorMsg::new(
            ErrorCode::InvalidArgument,
            format!("cannot build the match: {e}"),
        ),
    })?;
    Ok(ServerMsg::MatchCreated(MatchCreated { info }))
}
