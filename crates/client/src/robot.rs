//! The robot client loop: one team's players on a server, either as separate
//! robot connections (one per player, like real robots) or as one team
//! connection (the paper's central joint scheduling).

use std::fmt;
use std::sync::Arc;

use crate::net::{Client, ClientError};
use crate::policy::{Policy, PolicyKind};
use naosoccer_proto::msg::{MatchEnd, MatchId, Player};
use naosoccer_proto::{RobotId, Team};

/// Builds a policy for a robot from the match seed and the robot id.
pub type PolicyFactory = Arc<dyn Fn(u64, RobotId) -> Result<Box<dyn Policy>, String> + Send + Sync>;

/// The policy a team plays with: a built-in one, or any other (a trained
/// network, your own) through a factory.
#[derive(Clone)]
pub enum TeamPolicy {
    /// One instance per robot, seeded from the match seed and the robot id.
    Builtin(PolicyKind),
    /// A policy from `build`. With `batched`, a team connection builds one
    /// instance (for its first player) and asks it for all players at once
    /// through `Policy::act_batch`, so a network runs one forward pass per
    /// tick; otherwise every robot gets its own instance.
    Custom {
        name: String,
        batched: bool,
        build: PolicyFactory,
    },
}

impl TeamPolicy {
    pub fn name(&self) -> &str {
        match self {
            TeamPolicy::Builtin(k) => k.name(),
            TeamPolicy::Custom { name, .. } => name,
        }
    }
}

impl From<PolicyKind> for TeamPolicy {
    fn from(k: PolicyKind) -> Self {
        TeamPolicy::Builtin(k)
    }
}

impl fmt::Debug for TeamPolicy {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            TeamPolicy::Builtin(k) => f.debug_tuple("Builtin").field(k).finish(),
            TeamPolicy::Custom { name, batched, .. } => f
                .debug_struct("Custom")
                .field("name", name)
                .field("batched", batched)
                .finish_non_exhaustive(),
        }
    }
}

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
    pub policy: TeamPolicy,
    /// One connection for all players instead of one per player.
    pub team_connection: bool,
}

/// How one connection's match went.
#[derive(Debug, Clone, PartialEq)]
pub struct ConnectionResult {
    pub players: Vec<Player>,
    pub end: MatchEnd,
    /// Each player's return (sum of its rewards over the match), in the
    /// order of `players`.
    pub returns: Vec<f32>,
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

/// One connection: connect, join `players`, play with one policy instance
/// per robot (built from the match seed, as the in-process runner builds
/// them) or, for a batched custom policy, one for the connection; return the
/// match end.
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
    let robot = |p: &Player| RobotId::of(run.team, *p);
    let mut policies: Vec<Box<dyn Policy>> = match &run.policy {
        TeamPolicy::Builtin(kind) => joined
            .players
            .iter()
            .map(|p| kind.build(joined.seed, robot(p)))
            .collect(),
        TeamPolicy::Custom { batched, build, .. } => {
            let robots: Vec<RobotId> = if *batched {
                joined.players.iter().take(1).map(robot).collect()
            } else {
                joined.players.iter().map(robot).collect()
            };
            robots
                .into_iter()
                .map(|r| build(joined.seed, r).map_err(ClientError::Policies))
                .collect::<Result<_, _>>()?
        }
    };
    let played = client.play(&joined, &mut policies).await?;
    Ok(ConnectionResult {
        players,
        end: played.end,
        returns: played.returns,
    })
}
