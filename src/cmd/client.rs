//! `naosoccer client`: one team's robot clients.
use super::team::TeamSpec;
use anyhow::Context;
use clap::Args;
use naosoccer_client::robot::{run_team, TeamRun};
use naosoccer_proto::msg::{MatchId, Player};
use naosoccer_proto::Team;

#[derive(Args, Debug)]
#[command(after_help = "\
By default every player is its own robot connection (like real robots); \
--team-connection runs them all over one team connection instead (the paper's \
central scheduling). Without --match the clients join the oldest unfinished \
match whose slots are free. When the match ends the team's statistics are \
printed and the command exits 0.

--policy takes a built-in team (scripted, random, idle, or a scripted variant \
scripted:KEY=VAL,... or scripted:FILE.toml) or a trained one: \
ppo:DIR or dqn:DIR (a `naosoccer train` run directory, e.g. \
assets/policies/ppo-paper-seed1) or ppo:DIR/checkpoints/step-N.safetensors. A PPO \
team samples its actions (seeded by the match seed, so the match is \
repeatable); ppo-greedy:DIR takes the most likely action instead; a DQN team \
takes the largest Q-value (dqn-epsilon:DIR: epsilon-greedy with its training \
epsilon). A trained team over --team-connection runs all its \
players in one forward pass per tick.")]
pub struct ClientArgs {
    /// Server address.
    #[arg(long, value_name = "HOST:PORT", default_value = "127.0.0.1:7878")]
    pub server: String,
    /// The team these robots play for; its token (--token) must be that team's.
    #[arg(long, value_name = "blue|red")]
    pub team: Team,
    /// The team's token (printed by the server at start).
    #[arg(long, value_name = "TOKEN")]
    pub token: String,
    /// Match id to join.
    #[arg(long = "match", value_name = "ID")]
    pub match_id: Option<u64>,
    /// Players to run, comma-separated, 0..=3 (0 keeps goal).
    #[arg(long, value_delimiter = ',', default_value = "0,1,2,3")]
    pub players: Vec<u8>,
    /// The team's policy: scripted, scripted:KEY=VAL,..., scripted:FILE.toml,
    /// random, idle, or a trained team ppo:DIR / dqn:DIR.
    #[arg(long, value_name = "POLICY", default_value = "scripted")]
    pub policy: String,
    /// One connection for all players instead of one per player.
    #[arg(long)]
    pub team_connection: bool,
}

pub fn run(args: ClientArgs) -> anyhow::Result<()> {
    super::server::init_logging();
    let players = args
        .players
        .iter()
        .map(|&p| Player::try_from(p).map_err(anyhow::Error::msg))
        .collect::<anyhow::Result<Vec<_>>>()?;
    let run = TeamRun {
        server: args.server.clone(),
        team: args.team,
        token: args.token.clone(),
        match_id: args.match_id.map(MatchId),
        players,
        policy: TeamSpec::parse(&args.policy, "--policy")?.team_policy(),
        team_connection: args.team_connection,
    };
    let rt = tokio::runtime::Builder::new_multi_thread()
        .enable_all()
        .build()?;
    let results = rt
        .block_on(run_team(&run))
        .with_context(|| format!("playing on {}", args.server))?;
    let end = &results.first().context("no connection finished")?.end;
    let team = args.team;
    let s = end.stats.team(team);
    let misses: u64 = results
        .iter()
        .flat_map(|r| r.players.iter().map(|p| end.misses.get(team)[p.index()]))
        .sum();
    println!(
        "match {} {:?} after {} ticks: blue {} - {} red",
        end.match_id, end.reason, end.tick, end.score.blue, end.score.red
    );
    println!(
        "{team}: goals {}, ball control {:.1}% ({} ticks), passes {} ({} aimed), shots {}, falls {}, out of bounds {}, missed ticks {}",
        s.goals,
        100.0 * s.control_rate,
        s.control_ticks,
        s.passes,
        s.aimed_passes,
        s.shots,
        s.falls,
        s.out_of_bounds,
        misses
    );
    let mut returns: Vec<(u8, f32)> = results
        .iter()
        .flat_map(|r| {
            r.players
                .iter()
                .map(|p| p.index() as u8)
                .zip(r.returns.iter().copied())
        })
        .collect();
    returns.sort_by_key(|&(p, _)| p);
    let returns: Vec<String> = returns
        .iter()
        .map(|(p, r)| format!("robot {p} {r:.2}"))
        .collect();
    println!(
        "{team}: return (sum of the match configuration's reward): {}",
        returns.join(", ")
    );
    Ok(())
}
