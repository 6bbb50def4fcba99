//! The JSON messages of the naosoccer channels (see docs/RECORDINGS.md).

use naosoccer_proto::{
    Action, BallPlacement, MatchStats, RobotId, RobotPlacement, StateChange, Team, Tick, ROBOTS,
};
use naosoccer_referee::{Match, MatchConfig};
use serde::{Deserialize, Serialize};

/// Version of the channel layout; bumped when a message changes incompatibly,
/// or when the physics changes so that older recordings no longer replay.
/// 2: robots carry their torso `rotation`; feet, contacts and placements of
/// issue 12. 3: the Foxglove channels are the Foxglove SDK's protobuf types
/// (issue 16); the naosoccer channels are those of format 2.
pub const RECORDING_FORMAT: u32 = 3;

/// The oldest format this build reads and replays: format 2's naosoccer
/// channels are format 3's (only the Foxglove channels, which reading
/// skips, changed).
pub const OLDEST_READABLE_FORMAT: u32 = 2;

/// `/match/meta`, once at the start: everything re-simulation needs besides
/// the actions, and who played.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MatchMeta {
    pub format: u32,
    pub naosoccer_version: String,
    pub seed: u64,
    pub config: MatchConfig,
    /// What played each team (policy names or client descriptions).
    pub blue: String,
    pub red: String,
    /// `match` (in process) or `server`.
    pub source: String,
    /// The server's match id, if recorded by a server.
    #[serde(default)]
    pub match_id: Option<u64>,
    /// `lockstep` or `realtime` for server matches.
    #[serde(default)]
    pub mode: Option<String>,
    pub control_hz: f32,
    pub total_ticks: u64,
    /// The scenario the match started from (docs/SCENARIOS.md), if it did
    /// not start from the kick-off; absent otherwise.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub scenario: Option<ScenarioRecord>,
}

/// A recorded match's scenario: replay parses the file's text again and
/// starts the match from it with the recorded seed and colour.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ScenarioRecord {
    pub name: String,
    /// The colour the scenario's own team played.
    pub own: Team,
    /// The scenario file's text, as read.
    pub toml: String,
}

impl MatchMeta {
    /// The metadata of `m`, about to be played by `blue` and `red`, recorded
    /// by this build of naosoccer; `source` is `match` or `server`.
    pub fn of(m: &Match, blue: &str, red: &str, source: &str) -> MatchMeta {
        MatchMeta {
            format: RECORDING_FORMAT,
            naosoccer_version: env!("CARGO_PKG_VERSION").into(),
            seed: m.seed(),
            config: m.config().clone(),
            blue: blue.into(),
            red: red.into(),
            source: source.into(),
            match_id: None,
            mode: None,
            control_hz: m.config().control_hz,
            total_ticks: m.total_ticks(),
            scenario: m.scenario().map(|(name, toml, own)| ScenarioRecord {
                name: name.to_owned(),
                own,
                toml: toml.to_owned(),
            }),
        }
    }
}

/// `/match/actions`, every control tick: the actions applied to go from tick
/// `tick` to `tick + 1` (robots 0..=3 blue, 4..=7 red).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct TickActions {
    pub tick: Tick,
    pub actions: [Action; ROBOTS],
}

/// `/match/set_state`, for each state change an admin made (protocol 1.5's
/// `set_state`): the change as asked (world coordinates), applied before
/// tick `tick` was played. Replay applies it at the same point.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SetStateRecord {
    pub tick: Tick,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ball: Option<BallPlacement>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub robots: Vec<RobotPlacement>,
}

impl SetStateRecord {
    pub fn new(tick: Tick, change: &StateChange) -> SetStateRecord {
        SetStateRecord {
            tick,
            ball: change.ball,
            robots: change.robots.clone(),
        }
    }

    /// The change to re-apply.
    pub fn change(&self) -> StateChange {
        StateChange {
            ball: self.ball,
            robots: self.robots.clone(),
        }
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ScoreRecord {
    pub blue: u32,
    pub red: u32,
}

/// The ball in world coordinates (m, m/s).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct BallRecord {
    pub x: f32,
    pub y: f32,
    pub z: f32,
    pub vx: f32,
    pub vy: f32,
    pub vz: f32,
}

/// A robot's torso in world coordinates.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct RobotRecord {
    pub x: f32,
    pub y: f32,
    pub z: f32,
    /// Radians, 0 = facing +x (blue's attacking direction).
    pub heading: f32,
    /// Radians from upright.
    pub tilt: f32,
    /// The torso's orientation, a unit quaternion `[x, y, z, w]` (world from
    /// body: the body's x axis points forward, z up): which way a fallen
    /// robot lies.
    pub rotation: [f32; 4],
    pub fallen: bool,
}

/// `/match/state`, at tick 0 and after every control tick.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StateRecord {
    pub tick: Tick,
    /// Game seconds since kick-off.
    pub time: f64,
    pub score: ScoreRecord,
    /// The robot controlling the ball (the paper's `if_c`), if any.
    pub possession: Option<RobotId>,
    pub ball: BallRecord,
    pub robots: [RobotRecord; ROBOTS],
    /// `Match::state_hash`, 16 hex digits: what replay compares.
    pub state_hash: String,
}

impl StateRecord {
    pub fn of(m: &Match) -> StateRecord {
        let snap = m.sim().snapshot();
        let naosoccer_proto::PerTeam { blue, red } = m.score();
        let b = &snap.ball;
        StateRecord {
            tick: m.tick(),
            time: m.sim_seconds(),
            score: ScoreRecord { blue, red },
            possession: m.controller(),
            ball: BallRecord {
                x: b.pos[0],
                y: b.pos[1],
                z: b.pos[2],
                vx: b.vel[0],
                vy: b.vel[1],
                vz: b.vel[2],
            },
            robots: std::array::from_fn(|i| {
                let r = &snap.robots[i];
                RobotRecord {
                    x: r.pos[0],
                    y: r.pos[1],
                    z: r.pos[2],
                    heading: r.heading,
                    tilt: r.tilt,
                    rotation: r.rotation,
                    fallen: r.fallen,
                }
            }),
            state_hash: hash_hex(m.state_hash()),
        }
    }
}

/// `/match/stats`, once at the end.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FinalRecord {
    pub ticks: u64,
    pub score: ScoreRecord,
    pub stats: MatchStats,
    pub state_hash: String,
    /// False when the match was stopped before its clock ran out (server
    /// shutdown or a failure); the statistics are then those so far.
    pub completed: bool,
}

pub fn hash_hex(h: u64) -> String {
    format!("{h:016x}")
}
