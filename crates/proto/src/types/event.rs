//! What the referee reports: events, how goals came about, statistics.

use serde::{Deserialize, Serialize};

use super::{PerTeam, RobotId, SetPlayKind, Team, Tick};

/// How a goal came about (protocol 1.4), from the touches of the ball
/// since the last restart.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum GoalPhase {
    /// Anything that is not one of the two below.
    OpenPlay,
    /// From the scoring team's own restart (its kick-off or set play): only
    /// that team's robots touched the ball since the restart was awarded,
    /// and the goal came within `restart_goal_seconds` (15 s) of it.
    Restart,
    /// A robot of the conceding team touched the ball last.
    OwnGoal,
}

impl GoalPhase {
    pub const ALL: [GoalPhase; 3] = [GoalPhase::OpenPlay, GoalPhase::Restart, GoalPhase::OwnGoal];

    pub fn name(self) -> &'static str {
        match self {
            GoalPhase::OpenPlay => "open_play",
            GoalPhase::Restart => "restart",
            GoalPhase::OwnGoal => "own_goal",
        }
    }
}

/// Why a goal did not count (protocol 1.4).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum DisallowReason {
    /// Scored by the kicking team straight from its kick-off: no robot but
    /// the kicker had touched the ball since the kick-off (the SPL rule
    /// until 2022; `rules.direct_kick_off_goals` turns it off).
    DirectKickOff,
}

impl DisallowReason {
    pub fn name(self) -> &'static str {
        match self {
            DisallowReason::DirectKickOff => "direct_kick_off",
        }
    }
}

/// Something the referee saw happen, at a control tick. Positions are in
/// world coordinates (blue attacks +x).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Event {
    /// A goal for `team` (scored into the other team's goal). `scorer` is
    /// the robot of `team` that touched the ball last, `None` for an own
    /// goal (or a ball nobody touched).
    Goal {
        tick: Tick,
        team: Team,
        scorer: Option<RobotId>,
        /// How the goal came about (protocol 1.4; `None` from older peers).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        phase: Option<GoalPhase>,
    },
    /// The ball went into the goal but the goal does not count; play
    /// restarts with the set play that follows (a `SetPlay` event names
    /// it). `team` is the team it would have counted for. Protocol 1.4.
    GoalDisallowed {
        tick: Tick,
        team: Team,
        reason: DisallowReason,
    },
    /// A kick that moved the ball.
    Kick {
        tick: Tick,
        robot: RobotId,
        speed: f32,
        /// The teammate a `pass` was swung toward (the pass rule's receiver
        /// when the kick started); `None` for a shot, or a `pass` with no
        /// receiver (protocol 1.6; `None` from older peers).
        #[serde(default)]
        receiver: Option<RobotId>,
    },
    /// Possession moved between two teammates after a kick by the first.
    Pass {
        tick: Tick,
        from: RobotId,
        to: RobotId,
        /// How far the ball travelled from the kick to the reception, metres
        /// (protocol 1.2; read as 0 from older peers).
        #[serde(default)]
        distance: f32,
        /// `from`'s kick was a `pass` swung toward a receiver (protocol 1.6;
        /// `false` from older peers): a deliberate pass, whichever teammate
        /// took the ball.
        #[serde(default)]
        aimed: bool,
    },
    Fall {
        tick: Tick,
        robot: RobotId,
    },
    GetUp {
        tick: Tick,
        robot: RobotId,
    },
    /// The ball left the field; it was put back at (x, y) for the set play
    /// that follows (a `SetPlay` event names it). `last_touch` is the team
    /// whose robot touched it last, if known.
    BallOut {
        tick: Tick,
        x: f32,
        y: f32,
        last_touch: Option<Team>,
    },
    /// A robot left the field and was reset to its predetermined position.
    RobotOut {
        tick: Tick,
        robot: RobotId,
    },
    /// Play (re)starts from the centre: at the start and after each goal.
    KickOff {
        tick: Tick,
        team: Team,
    },
    /// A set play was awarded to `team` with the ball placed at (x, y)
    /// (kick-offs have their own event). Protocol 1.2.
    SetPlay {
        tick: Tick,
        play: SetPlayKind,
        team: Team,
        x: f32,
        y: f32,
    },
    /// The first half is over; the second starts with a kick-off by the team
    /// that did not kick off the first. Protocol 1.2.
    HalfTime {
        tick: Tick,
    },
    /// The clock ran out.
    End {
        tick: Tick,
    },
    /// An admin set the state of the match (`set_state`; protocol 1.5)
    /// before this tick was played: the tick was played from the new state.
    StateSet {
        tick: Tick,
    },
    /// An event of a kind this build does not know: a later server's (a
    /// minor version may add kinds; docs/PROTOCOL.md, "Events"). Read so
    /// that the message holding it still decodes; skip it. Its fields are
    /// dropped, and the referee never produces it.
    #[serde(other)]
    Unknown,
}

impl Event {
    /// The tick the event happened on (`None` for [`Event::Unknown`]).
    pub fn tick(&self) -> Option<Tick> {
        Some(match self {
            Event::Goal { tick, .. }
            | Event::GoalDisallowed { tick, .. }
            | Event::Kick { tick, .. }
            | Event::Pass { tick, .. }
            | Event::Fall { tick, .. }
            | Event::GetUp { tick, .. }
            | Event::BallOut { tick, .. }
            | Event::RobotOut { tick, .. }
            | Event::KickOff { tick, .. }
            | Event::SetPlay { tick, .. }
            | Event::HalfTime { tick }
            | Event::End { tick }
            | Event::StateSet { tick } => *tick,
            Event::Unknown => return None,
        })
    }
}

/// One team's statistics over a match.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Default)]
pub struct TeamStats {
    pub goals: u32,
    /// Ticks this team controlled the ball / ticks any team controlled it, in [0, 1].
    pub control_rate: f64,
    /// Ticks this team controlled the ball.
    pub control_ticks: u64,
    pub passes: u32,
    /// Of `passes`, those whose kick was a `pass` swung toward a receiver
    /// (protocol 1.6; 0 from older peers).
    #[serde(default)]
    pub aimed_passes: u32,
    pub shots: u32,
    pub falls: u32,
    pub out_of_bounds: u32,
    /// Set plays awarded to this team (protocol 1.2; 0 from older peers).
    #[serde(default)]
    pub kick_ins: u32,
    #[serde(default)]
    pub goal_kicks: u32,
    #[serde(default)]
    pub corner_kicks: u32,
    /// This team's goals by phase (protocol 1.4; 0 from older peers):
    /// from open play, from its own restarts, and the other team's own
    /// goals. The three sum to `goals`.
    #[serde(default)]
    pub goals_open_play: u32,
    #[serde(default)]
    pub goals_restart: u32,
    #[serde(default)]
    pub goals_own_goal: u32,
    /// Goals of this team that did not count (protocol 1.4).
    #[serde(default)]
    pub goals_disallowed: u32,
}

/// Goals per team, in world terms (not mirrored).
pub type Score = PerTeam<u32>;

/// Both teams' statistics.
pub type MatchStats = PerTeam<TeamStats>;

impl MatchStats {
    /// [`PerTeam::get`] under the name statistics have always used.
    pub fn team(&self, team: Team) -> &TeamStats {
        self.get(team)
    }
    pub fn team_mut(&mut self, team: Team) -> &mut TeamStats {
        self.get_mut(team)
    }
}
