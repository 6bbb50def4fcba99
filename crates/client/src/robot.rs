//! The robot client loop: one team's players on a server, either as separate
//! robot connections (one per player, like real robots) or as one team
//! connection (the paper's central joint scheduling).

use crate::net::{Client, ClientError};
use crate::policy::{Policy, PolicyKind};
use naosoccer_proto::msg::{MatchEnd, MatchId, Player};
use naosoccer_proto::{RobotId, Team};

/// What to run.
#[derive(Debug, Clone)]
pub struct TeamRun {
    /// `HOST:PORT`.
    pub server: String,
    pub team: Team,
    pub token: String,
    /// `None`: the oldest unfinished match with these slots free.
    pub match_id: Option<MatchId>,
    pub players: Vec<Player>,
    pub policy: PolicyKind,
    /// One connection for all players instead of one per player.
    pub team_connection: bool,
}

/// How one connection's match went.
#[derive(Debug, Clone, PartialEq)]
pub struct ConnectionResult {
    pub players: Vec<Player>,
    pub end: MatchEnd,
}

/// Runs the players until the match ends. Each connection's result, in the
/// order of `players` (one entry for a team connection).
pub async fn run_team(run: &TeamRun) -> Result<Vec<ConnectionResult>, ClientError> {
    if run.players.is_empty() {
        return Err(ClientError::Policies("no players to run".into()));
    }
    let groups: Vec<Vec<Player>> = if run.team_connection {
        vec![run.players.clone()]
    } else {
        run.players.iter().map(|&p| vec![p]).collect()
    };
    let mut tasks = Vec::with_capacity(groups.len());
    for players in groups {
        let run = run.clone();
        tasks.push(tokio::spawn(
            async move { play_connection(&run, players).await },
        ));
    }
    let mut results = Vec::with_capacity(tasks.len());
    let mut first_err = None;
    for t in tasks {
        match t.await {
            Ok(Ok(r)) => results.push(r),
            Ok(Err(e)) => {
                first_err.get_or_insert(e);
            }
            Err(join) => {
                first_err.get_or_insert(ClientError::Unexpected(format!(
                    "robot task failed: {join}"
                )));
            }
        }
    }
    match first_err {
        Some(e) => Err(e),
        None => Ok(results),
    }
}

/// One connection: connect, join `players`, play with one built-in policy
/// instance per robot (seeded from the match seed, as the in-process runner
/// does), return the match end.
pub async fn play_connection(
    run: &TeamRun,
    players: Vec<Player>,
) -> Result<ConnectionResult, ClientError> {
    let name = format!(
        "naosoccer-client {} {:?}",
        run.team,
        players.iter().map(|p| p.index()).collect::<Vec<_>>()
    );
    let mut client = Client::connect(run.server.as_str(), &name).await?;
    let joined = client
        .join(run.match_id, run.team, &run.token, &players)
        .await?;
    tracing::info!(match_id = %joined.match_id, team = %run.team, ?players, "joined");
    let mut policies: Vec<Box<dyn Policy>> = joined
        .players
        .iter()
        .map(|p| {
            let robot = RobotId::new(run.team, p.index()).expect("player numbers are validated");
            run.policy.build(joined.seed, robot)
        })
        .collect();
    let end = client.play(&joined, &mut policies).await?;
    Ok(ConnectionResult { players, end })
}
