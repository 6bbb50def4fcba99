//! Helpers shared by the server tests (`common::server`): a real
//! server on 127.0.0.1:0 and the in-process reference match.

use naosoccer_client::{Client, Push};
use naosoccer_policy::PolicyKind;
use naosoccer_proto::msg::Score;
use naosoccer_proto::msg::{CreateMatch, ErrorMsg, Fill, MatchEnd, MatchId, Player, PlayerAction};
use naosoccer_proto::Action;
use naosoccer_proto::MatchStats;
use naosoccer_referee::MatchConfig;
use naosoccer_server::{ServerConfig, ServerError, TokenConfig};
use std::net::SocketAddr;
use tokio::net::TcpListener;
use tokio::sync::oneshot;
use tokio::task::JoinHandle;

pub const BLUE: &str = "blue-secret";
pub const RED: &str = "red-secret";
pub const ADMIN: &str = "admin-secret";

pub struct TestServer {
    pub addr: SocketAddr,
    stop: Option<oneshot::Sender<()>>,
    task: JoinHandle<Result<(), ServerError>>,
}

/// A server config with fixed tokens and a short match of `ticks` ticks.
pub fn config(ticks: u32) -> ServerConfig {
    let mut cfg = ServerConfig {
        tokens: TokenConfig {
            blue: Some(BLUE.into()),
            red: Some(RED.into()),
            admin: Some(ADMIN.into()),
        },
        seed: 42,
        // Lockstep ticks wait a minute for actions, not the default second:
        // on a loaded machine (a panicking match printing its backtrace, a
        // training run beside the suite) a prompt client can take longer,
        // and its robots would "stay". Tests of the deadline set their own.
        deadline_ms: 60_000,
        ..ServerConfig::default()
    };
    cfg.match_cfg.minutes = ticks as f32 / (60.0 * cfg.match_cfg.control_hz);
    cfg
}

pub async fn start(cfg: ServerConfig) -> TestServer {
    let listener = TcpListener::bind("127.0.0.1:0").await.unwrap();
    let addr = listener.local_addr().unwrap();
    let (tx, rx) = oneshot::channel::<()>();
    let task = tokio::spawn(naosoccer_server::run(listener, cfg, async move {
        let _ = rx.await;
    }));
    TestServer {
        addr,
        stop: Some(tx),
        task,
    }
}

impl TestServer {
    pub fn addr(&self) -> String {
        self.addr.to_string()
    }

    /// Triggers graceful shutdown and waits until the server has finished.
    pub async fn stop(mut self) {
        let _ = self.stop.take().unwrap().send(());
        self.task.await.unwrap().unwrap();
    }
}

/// The same match played in process by the CLI's runner (`naosoccer match`):
/// stats, score, ticks and the final state hash as `match_end` writes it.
pub fn in_process(
    cfg: &MatchConfig,
    seed: u64,
    blue: PolicyKind,
    red: PolicyKind,
) -> (MatchStats, Score, u64, String) {
    let out = naosoccer_eval::run::play_match(cfg, seed, &blue, &red, |_| {}).unwrap();
    let score = Score {
        blue: out.score.blue,
        red: out.score.red,
    };
    (
        out.stats,
        score,
        out.ticks,
        format!("{:016x}", out.state_hash),
    )
}

/// Player `n` of a team.
pub fn p(n: usize) -> Player {
    Player::new(n).unwrap()
}

/// `stay` for each of `players`.
pub fn stay(players: &[Player]) -> Vec<PlayerAction> {
    players
        .iter()
        .map(|&player| PlayerAction {
            player,
            action: Action::Stay,
        })
        .collect()
}

/// Plays the joined players with `stay` until the match ends; returns the
/// end and the non-fatal errors pushed on the way.
pub async fn play_out(c: &mut Client, players: &[Player]) -> (MatchEnd, Vec<ErrorMsg>) {
    let actions = stay(players);
    let mut errors = Vec::new();
    loop {
        match c.next_push().await.unwrap() {
            Push::Observation(o) => c.send_actions(o.tick, &actions).await.unwrap(),
            Push::MatchEnd(end) => return (end, errors),
            Push::Error(e) => errors.push(e),
        }
    }
}

/// A client named `name` that joined match 1 for `player` of `team`.
pub async fn join_robot(
    server: &TestServer,
    name: &str,
    team: naosoccer_proto::Team,
    token: &str,
    player: Player,
) -> Client {
    let mut c = Client::connect(server.addr(), name).await.unwrap();
    c.join(
        Some(naosoccer_proto::msg::MatchId(1)),
        team,
        token,
        &[player],
    )
    .await
    .unwrap();
    c
}

/// A server whose 600-tick matches wait a long while for their clients'
/// actions (each tick waits for blue), with one match an admin created,
/// which starts once `start_players` players joined (the other slots
/// `idle`): the server, the admin connection and the match's id.
pub async fn idle_match_waiting_for(start_players: u8) -> (TestServer, Client, MatchId) {
    let mut cfg = config(600);
    cfg.deadline_ms = 600_000; // each tick waits for blue
    let server = start(cfg).await;
    let mut admin = Client::connect(server.addr(), "admin").await.unwrap();
    let info = admin
        .create_match(CreateMatch {
            token: ADMIN.into(),
            fill: Some(Fill::Idle),
            start_players: Some(start_players),
            ..CreateMatch::default()
        })
        .await
        .unwrap();
    (server, admin, info.match_id)
}

/// [`idle_match_waiting_for`] four players, with blue's four joined to
/// it: the server, the admin and blue connections, and the match's id.
pub async fn blue_waits_in_an_idle_match() -> (TestServer, Client, Client, MatchId) {
    let (server, admin, id) = idle_match_waiting_for(4).await;
    let team: Vec<Player> = Player::all().collect();
    let mut blue = Client::connect(server.addr(), "blue").await.unwrap();
    blue.join(Some(id), naosoccer_proto::Team::Blue, BLUE, &team)
        .await
        .unwrap();
    (server, admin, blue, id)
}
