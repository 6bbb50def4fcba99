//! `action`: the answer to an observation, checked here (players this
//! connection controls, a tick it has seen) and forwarded to the match.
//! An accepted action has no reply.

use crate::match_msg::MatchCmd;
use crate::session::Session;
use naosoccer_proto::msg::{ActionMsg, ErrorCode, ErrorMsg};
use naosoccer_proto::{Action, PLAYERS_PER_TEAM};

pub(crate) async fn handle(s: &mut Session, a: ActionMsg) -> Result<(), ErrorMsg> {
    let with_tick = |e: ErrorMsg| ErrorMsg {
        tick: Some(a.tick),
        ..e
    };
    let Some(seat) = &s.seat else {
        return Err(with_tick(ErrorMsg::new(
            ErrorCode::FailedPrecondition,
            "join a match before sending actions",
        )));
    };
    if let Some(team) = a.team {
        if team != seat.team {
            let m = format!(
                "this connection plays for {}; it cannot act for {team}",
                seat.team
            );
            return Err(with_tick(ErrorMsg::new(ErrorCode::PermissionDenied, m)));
        }
    }
    let mut actions: [Option<Action>; PLAYERS_PER_TEAM] = [None; PLAYERS_PER_TEAM];
    for pa in &a.actions {
        if !seat.players.contains(&pa.player) {
            let m = format!(
                "{} player {} is not controlled by this connection",
                seat.team, pa.player
            );
            return Err(with_tick(ErrorMsg::new(ErrorCode::PermissionDenied, m)));
        }
        if actions[pa.player.index()].replace(pa.action).is_some() {
            let m = format!("two actions for player {}", pa.player);
            return Err(with_tick(ErrorMsg::new(ErrorCode::InvalidArgument, m)));
        }
    }
    match seat.observed {
        None => {
            let m = "no observation yet: the match has not started";
            return Err(with_tick(ErrorMsg::new(ErrorCode::FailedPrecondition, m)));
        }
        Some(t) if a.tick > t => {
            let m = format!(
                "tick {} is in the future (last observation: tick {t})",
                a.tick
            );
            return Err(with_tick(ErrorMsg::new(ErrorCode::InvalidArgument, m)));
        }
        Some(_) => {}
    }
    // A send error means the match just ended; its match_end is on the way.
    let _ = seat
        .tx
        .send(MatchCmd::Action {
            conn: s.id,
            team: seat.team,
            tick: a.tick,
            actions,
        })
        .await;
    Ok(())
}
