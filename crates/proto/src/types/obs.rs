//! What a player sees every control tick: the observation and its parts.

use serde::{Deserialize, Serialize};

use super::{Player, Team, Tick, PLAYERS_PER_TEAM};

/// One robot as a player sees it, in the observing team's frame.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Default)]
pub struct RobotObs {
    /// Position on the pitch in metres; the observing team attacks +x.
    pub x: f32,
    pub y: f32,
    /// Heading in radians in (-pi, pi], 0 = facing +x (the opponent goal).
    pub heading: f32,
    /// Lying on the pitch (waiting to get up).
    pub fallen: bool,
    /// In a kick (wind-up or recovery): the robot finishes it before any new
    /// action takes effect. Protocol 1.2; absent from older peers, read as false.
    #[serde(default)]
    pub busy: bool,
}

/// The ball as a player sees it, in the observing team's frame.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Default)]
pub struct BallObs {
    pub x: f32,
    pub y: f32,
    /// Velocity in m/s.
    pub vx: f32,
    pub vy: f32,
}

/// Goals so far, from the observing team's side.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
pub struct ScoreObs {
    pub own: u32,
    pub opponent: u32,
}

/// What one player receives every control tick. The paper's state
/// `s_t = [P, p_ball, if_c, P_oppo]` plus headings, fall flags, score and clock.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Observation {
    /// Control tick this observation was taken at (before the action is applied).
    pub tick: Tick,
    pub team: Team,
    /// Which of `own` is the receiving robot (0..=3; a number on the wire).
    pub player: Player,
    /// Match time left in seconds.
    pub time_left: f32,
    pub score: ScoreObs,
    /// Own robots, indexed by player number.
    pub own: [RobotObs; PLAYERS_PER_TEAM],
    /// Opponent robots, indexed by their player number.
    pub opponents: [RobotObs; PLAYERS_PER_TEAM],
    pub ball: BallObs,
    /// The paper's `if_c`: which own robot controls the ball (at most one true).
    pub control: [bool; PLAYERS_PER_TEAM],
    /// Whether an opponent controls the ball.
    pub opponent_control: bool,
    /// This robot's reward for the tick that led to this observation (the
    /// match configuration's `[reward]`, the learning crate's MDP); 0 on the
    /// first tick. Protocol 1.1; absent from 1.0 peers, read as 0.
    #[serde(default)]
    pub reward: f32,
    /// The half being played, 1 or 2. Protocol 1.2; absent from older peers,
    /// read as 0.
    #[serde(default)]
    pub half: u8,
    /// The set play in progress, if any: while it lasts the team that does
    /// not take it must keep its distance from the ball. Protocol 1.2.
    #[serde(default)]
    pub set_play: Option<SetPlayObs>,
}

/// The SPL restarts. Kick-off: from the centre spot, at the start of each
/// half and after a goal. Kick-in: the ball left over a touch line. Goal
/// kick: over a goal line (not a goal), last touched by the attackers.
/// Corner kick: over a goal line, last touched by the defenders.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SetPlayKind {
    KickOff,
    KickIn,
    GoalKick,
    CornerKick,
}

impl SetPlayKind {
    pub const ALL: [SetPlayKind; 4] = [
        SetPlayKind::KickOff,
        SetPlayKind::KickIn,
        SetPlayKind::GoalKick,
        SetPlayKind::CornerKick,
    ];

    pub fn name(self) -> &'static str {
        match self {
            SetPlayKind::KickOff => "kick_off",
            SetPlayKind::KickIn => "kick_in",
            SetPlayKind::GoalKick => "goal_kick",
            SetPlayKind::CornerKick => "corner_kick",
        }
    }

    /// Index in [`SetPlayKind::ALL`].
    pub fn index(self) -> usize {
        match self {
            SetPlayKind::KickOff => 0,
            SetPlayKind::KickIn => 1,
            SetPlayKind::GoalKick => 2,
            SetPlayKind::CornerKick => 3,
        }
    }
}

/// A set play as a player sees it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SetPlayObs {
    pub kind: SetPlayKind,
    /// Whether the observing team takes it.
    pub own: bool,
    /// Control ticks until the other team may approach the ball anyway (the
    /// set play also ends as soon as the ball is played).
    pub ticks_left: u32,
}

impl Observation {
    /// The receiving robot.
    pub fn me(&self) -> &RobotObs {
        &self.own[self.player.index()]
    }
}
