//! Protocol 1.2's additions over a real server on an ephemeral loopback
//! port (issue 15 B): the pitch announced in `joined`.

#[path = "server_support.rs"]
mod support;

use naosoccer_client::Client;
use naosoccer_proto::msg::{Frame, MatchId, Pitch, Player};
use naosoccer_proto::Team;
use support::*;

fn all_players() -> Vec<Player> {
    Player::all().collect()
}

/// `joined` carries the pitch of the server's match configuration, so a
/// client needs no copy of it; a configuration other than the default shows
/// it is read from the match, not hard-wired.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn joined_announces_the_pitch() {
    let mut cfg = config(20);
    cfg.start_players = 8; // nothing is played: only the reply matters
    cfg.match_cfg.sim.field_length = 7.5;
    cfg.match_cfg.sim.field_width = 5.0;
    cfg.match_cfg.sim.goal_width = 1.5;
    cfg.match_cfg.rules.b_d = 0.25;
    cfg.match_cfg.rules.b_rad = 0.5;
    cfg.match_cfg.control_hz = 5.0;
    let sim = cfg.match_cfg.sim.clone();
    let server = start(cfg).await;
    let mut c = Client::connect(server.addr(), "pitch").await.unwrap();
    let joined = c
        .join(Some(MatchId(1)), Team::Red, RED, &all_players())
        .await
        .unwrap();
    assert_eq!(joined.control_hz, 5.0);
    assert_eq!(
        joined.pitch,
        Some(Pitch {
            field_length: 7.5,
            field_width: 5.0,
            goal_width: 1.5,
            goal_depth: sim.goal_depth,
            goal_height: sim.goal_height,
            ball_radius: sim.ball_radius,
            b_d: 0.25,
            b_rad: 0.5,
            frame: Frame::Team,
        })
    );
    drop(c);
    server.stop().await;
}
