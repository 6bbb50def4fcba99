//! `join`: takes players of a team in a match (team token); the match then
//! pushes their observations to this connection.

use crate::config::token_eq;
use crate::match_msg::MatchCmd;
use crate::session::{Seat, Session};
use naosoccer_proto::msg::{ErrorCode, ErrorMsg, Join, ServerMsg};
use naosoccer_proto::PLAYERS_PER_TEAM;
use tokio::sync::{mpsc, oneshot};

pub(crate) async fn handle(s: &mut Session, j: Join) -> Result<ServerMsg, ErrorMsg> {
    if !token_eq(&j.token, s.shared.tokens.team(j.team)) {
        return Err(ErrorMsg::new(
            ErrorCode::PermissionDenied,
            format!("wrong token for team {}", j.team),
        ));
    }
    if let Some(seat) = &s.seat {
        let m = format!(
            "this connection already plays in match {}; leave first",
            seat.match_id
        );
        return Err(ErrorMsg::new(ErrorCode::FailedPrecondition, m));
    }
    if j.players.is_empty() {
        return Err(ErrorMsg::new(
            ErrorCode::InvalidArgument,
            "players is empty",
        ));
    }
    let mut seen = [false; PLAYERS_PER_TEAM];
    for p in &j.players {
        if std::mem::replace(&mut seen[p.index()], true) {
            return Err(ErrorMsg::new(
                ErrorCode::InvalidArgument,
                format!("player {p} listed twice"),
            ));
        }
    }
    let max_joins = s.shared.config.limits.max_joins_per_connection;
    if s.joins >= max_joins {
        let m = format!("this connection already joined {max_joins} times (max_joins_per_connection); reconnect to join again");
        return Err(ErrorMsg::new(ErrorCode::ResourceExhausted, m));
    }
    let (match_id, tx) = s.shared.find_match(j.match_id, j.team, &j.players)?;
    let finished = || {
        ErrorMsg::new(
            ErrorCode::FailedPrecondition,
            format!("match {match_id} has finished"),
        )
    };
    let (out_tx, out_rx) = mpsc::channel(s.shared.config.limits.max_outbound);
    let (kick_tx, kick_rx) = oneshot::channel();
    let (reply_tx, reply_rx) = oneshot::channel();
    let cmd = MatchCmd::Join {
        conn: s.id,
        team: j.team,
        players: j.players.clone(),
        out: out_tx,
        kick: kick_tx,
        reply: reply_tx,
    };
    tx.send(cmd).await.map_err(|_| finished())?;
    let joined = reply_rx.await.map_err(|_| finished())??;
    s.joins += 1;
    s.seat = Some(Seat {
        match_id,
        team: j.team,
        players: j.players,
        tx,
        out: out_rx,
        kicked: kick_rx,
        kick_gone: false,
        observed: None,
    });
    Ok(ServerMsg::Joined(joined))
}
