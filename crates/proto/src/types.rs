//! Game-level wire types: ids, ticks, actions, observations, events,
//! statistics.

use serde::{Deserialize, Serialize};
use std::fmt;

/// Robots a team fields.
pub const PLAYERS_PER_TEAM: usize = 4;
/// Robots on the pitch.
pub const ROBOTS: usize = 2 * PLAYERS_PER_TEAM;

/// A team. In world coordinates blue attacks +x (its own goal is at -x).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Team {
    Blue,
    Red,
}

impl Team {
    pub const BOTH: [Team; 2] = [Team::Blue, Team::Red];

    pub fn other(self) -> Team {
        match self {
            Team::Blue => Team::Red,
            Team::Red => Team::Blue,
        }
    }

    /// 0 for blue, 1 for red.
    pub fn index(self) -> usize {
        match self {
            Team::Blue => 0,
            Team::Red => 1,
        }
    }

    /// +1 for blue (attacks +x in world coordinates), -1 for red.
    pub fn direction(self) -> f32 {
        match self {
            Team::Blue => 1.0,
            Team::Red => -1.0,
        }
    }
}

impl fmt::Display for Team {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Team::Blue => "blue",
            Team::Red => "red",
        })
    }
}

impl std::str::FromStr for Team {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s {
            "blue" => Ok(Team::Blue),
            "red" => Ok(Team::Red),
            other => Err(format!("unknown team {other:?} (expected blue or red)")),
        }
    }
}

/// A robot on the pitch: 0..=3 are blue players 0..=3, 4..=7 red players 0..=3.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
#[serde(try_from = "u8", into = "u8")]
pub struct RobotId(u8);

impl RobotId {
    pub fn new(team: Team, player: usize) -> Option<RobotId> {
        (player < PLAYERS_PER_TEAM)
            .then(|| RobotId((team.index() * PLAYERS_PER_TEAM + player) as u8))
    }
    pub fn from_index(i: usize) -> Option<RobotId> {
        (i < ROBOTS).then_some(RobotId(i as u8))
    }
    pub fn index(self) -> usize {
        self.0 as usize
    }
    pub fn team(self) -> Team {
        if (self.0 as usize) < PLAYERS_PER_TEAM {
            Team::Blue
        } else {
            Team::Red
        }
    }
    /// Player number within the team, 0..=3.
    pub fn player(self) -> usize {
        self.0 as usize % PLAYERS_PER_TEAM
    }
    pub fn all() -> impl Iterator<Item = RobotId> {
        (0..ROBOTS as u8).map(RobotId)
    }
}

impl TryFrom<u8> for RobotId {
    type Error = String;
    fn try_from(v: u8) -> Result<Self, Self::Error> {
        RobotId::from_index(v as usize)
            .ok_or_else(|| format!("robot id {v} out of range 0..{ROBOTS}"))
    }
}

impl From<RobotId> for u8 {
    fn from(r: RobotId) -> u8 {
        r.0
    }
}

/// A player number within a team, 0..=3; validated when deserialised.
#[derive(Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
#[serde(try_from = "u8", into = "u8")]
pub struct Player(u8);

impl Player {
    pub fn new(n: usize) -> Option<Player> {
        (n < PLAYERS_PER_TEAM).then_some(Player(n as u8))
    }
    pub fn index(self) -> usize {
        self.0 as usize
    }
    pub fn all() -> impl Iterator<Item = Player> {
        (0..PLAYERS_PER_TEAM as u8).map(Player)
    }
}

impl TryFrom<u8> for Player {
    type Error = String;
    fn try_from(v: u8) -> Result<Self, Self::Error> {
        Player::new(v as usize)
            .ok_or_else(|| format!("player {v} out of range 0..{PLAYERS_PER_TEAM}"))
    }
}

impl From<Player> for u8 {
    fn from(p: Player) -> u8 {
        p.0
    }
}

impl fmt::Debug for Player {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.0)
    }
}

impl fmt::Display for Player {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.0)
    }
}

impl RobotId {
    /// A team's player: always a robot on the pitch.
    pub fn of(team: Team, player: Player) -> RobotId {
        RobotId((team.index() * PLAYERS_PER_TEAM + player.index()) as u8)
    }

    /// The player number within its team.
    pub fn player_id(self) -> Player {
        Player(self.0 % PLAYERS_PER_TEAM as u8)
    }
}

/// A control tick of a match: 0 is the first observation, and a match of
/// `total_ticks` ends at tick `total_ticks`. On the wire a plain number
/// (`serde(transparent)`). Durations in ticks (`total_ticks`, `ticks_left`,
/// a fall's stand-up time) stay plain integers: a `Tick` plus a count is a
/// `Tick`, and two ticks subtract to a count.
#[derive(Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Default, Serialize, Deserialize)]
#[serde(transparent)]
pub struct Tick(u64);

impl Tick {
    /// The first tick of a match.
    pub const ZERO: Tick = Tick(0);

    pub const fn new(n: u64) -> Tick {
        Tick(n)
    }
    /// The tick number.
    pub const fn get(self) -> u64 {
        self.0
    }
    /// The tick after this one.
    pub const fn next(self) -> Tick {
        Tick(self.0 + 1)
    }
    /// The tick before this one (`None` at tick 0).
    pub const fn prev(self) -> Option<Tick> {
        match self.0.checked_sub(1) {
            Some(n) => Some(Tick(n)),
            None => None,
        }
    }
    /// Ticks from `earlier` to this one, 0 if `earlier` is later.
    pub const fn saturating_since(self, earlier: Tick) -> u64 {
        self.0.saturating_sub(earlier.0)
    }
}

impl From<u64> for Tick {
    fn from(n: u64) -> Tick {
        Tick(n)
    }
}

impl From<Tick> for u64 {
    fn from(t: Tick) -> u64 {
        t.0
    }
}

/// A tick some ticks later.
impl std::ops::Add<u64> for Tick {
    type Output = Tick;
    fn add(self, ticks: u64) -> Tick {
        Tick(self.0 + ticks)
    }
}

impl std::ops::AddAssign<u64> for Tick {
    fn add_assign(&mut self, ticks: u64) {
        self.0 += ticks;
    }
}

/// The ticks between two ticks (`later - earlier`; overflows as `u64` does
/// when `earlier` is later).
impl std::ops::Sub for Tick {
    type Output = u64;
    fn sub(self, earlier: Tick) -> u64 {
        self.0 - earlier.0
    }
}

/// The tick some ticks earlier (overflows as `u64` does before tick 0).
impl std::ops::Sub<u64> for Tick {
    type Output = Tick;
    fn sub(self, ticks: u64) -> Tick {
        Tick(self.0 - ticks)
    }
}

impl fmt::Debug for Tick {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.0)
    }
}

impl fmt::Display for Tick {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.0)
    }
}

/// One value per team.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
pub struct PerTeam<T> {
    pub blue: T,
    pub red: T,
}

impl<T> PerTeam<T> {
    pub fn get(&self, team: Team) -> &T {
        match team {
            Team::Blue => &self.blue,
            Team::Red => &self.red,
        }
    }
    pub fn get_mut(&mut self, team: Team) -> &mut T {
        match team {
            Team::Blue => &mut self.blue,
            Team::Red => &mut self.red,
        }
    }
}

/// The paper's five actions, and `pass` (protocol 1.3): a kick toward the
/// teammate [`pass_receiver`] names. One holds for one control tick.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize, Default,
)]
#[serde(rename_all = "snake_case")]
pub enum Action {
    Forward,
    TurnLeft,
    TurnRight,
    Shoot,
    #[default]
    Stay,
    /// Kick toward the teammate [`pass_receiver`] names, at a speed that
    /// rolls the ball about half a metre past it; with no such teammate, a
    /// `shoot`. Protocol 1.3.
    Pass,
}

impl Action {
    /// Every action, in index order.
    pub const ALL: [Action; 6] = [
        Action::Forward,
        Action::TurnLeft,
        Action::TurnRight,
        Action::Shoot,
        Action::Stay,
        Action::Pass,
    ];

    /// The paper's five actions (the first five of [`Action::ALL`]).
    pub const PAPER: [Action; 5] = [
        Action::Forward,
        Action::TurnLeft,
        Action::TurnRight,
        Action::Shoot,
        Action::Stay,
    ];

    /// Index in [`Action::ALL`] (the learning crate's discrete action id).
    pub fn index(self) -> usize {
        match self {
            Action::Forward => 0,
            Action::TurnLeft => 1,
            Action::TurnRight => 2,
            Action::Shoot => 3,
            Action::Stay => 4,
            Action::Pass => 5,
        }
    }

    pub fn from_index(i: usize) -> Option<Action> {
        Action::ALL.get(i).copied()
    }

    pub fn name(self) -> &'static str {
        match self {
            Action::Forward => "forward",
            Action::TurnLeft => "turn_left",
            Action::TurnRight => "turn_right",
            Action::Shoot => "shoot",
            Action::Stay => "stay",
            Action::Pass => "pass",
        }
    }
}

impl std::str::FromStr for Action {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Action::ALL
            .into_iter()
            .find(|a| a.name() == s)
            .ok_or_else(|| format!("unknown action {s:?}"))
    }
}

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

/// Who a `pass` goes to: the teammates it may reach and how it picks one.
/// A candidate is a standing teammate other than the kicker, between
/// [`PASS_MIN_DISTANCE`] and [`PASS_MAX_DISTANCE`] from the ball, whose
/// direction from the ball lies within [`PASS_CONE`] of the kicker's heading,
/// with no opponent (standing or lying) within [`PASS_LANE`] of the straight
/// line from the ball to it. Of the candidates the one nearest the opponent
/// goal (largest `x` in the team frame) receives; on a tie, the lower player
/// number.
pub const PASS_MIN_DISTANCE: f32 = 0.8;
/// See [`PASS_MIN_DISTANCE`].
pub const PASS_MAX_DISTANCE: f32 = 4.0;
/// See [`PASS_MIN_DISTANCE`]; radians either side of the heading.
pub const PASS_CONE: f32 = 0.8;
/// See [`PASS_MIN_DISTANCE`]; metres either side of the lane.
pub const PASS_LANE: f32 = 0.3;

/// The teammate (player number) a `pass` by the robot that received `obs`
/// would go to, if any: see [`PASS_MIN_DISTANCE`] for the rule. Computed
/// from the observation alone, so a client knows whether `pass` is a pass
/// before sending it; the referee applies the same function to the
/// kicker's observation.
pub fn pass_receiver(obs: &Observation) -> Option<usize> {
    let me = obs.player.index();
    let heading = obs.own[me].heading;
    let (bx, by) = (obs.ball.x, obs.ball.y);
    let mut best: Option<(usize, f32)> = None;
    for (j, r) in obs.own.iter().enumerate() {
        if j == me || r.fallen {
            continue;
        }
        let (dx, dy) = (r.x - bx, r.y - by);
        let d = dx.hypot(dy);
        if !(PASS_MIN_DISTANCE..=PASS_MAX_DISTANCE).contains(&d) {
            continue;
        }
        let mut off = dy.atan2(dx) - heading;
        off = (off + std::f32::consts::PI).rem_euclid(std::f32::consts::TAU) - std::f32::consts::PI;
        if off.abs() > PASS_CONE {
            continue;
        }
        let blocked = obs.opponents.iter().any(|o| {
            // Distance from the opponent to the segment ball -> teammate.
            let t = (((o.x - bx) * dx + (o.y - by) * dy) / (d * d)).clamp(0.0, 1.0);
            (o.x - (bx + t * dx)).hypot(o.y - (by + t * dy)) <= PASS_LANE
        });
        if blocked {
            continue;
        }
        if best.is_none_or(|(_, x)| r.x > x) {
            best = Some((j, r.x));
        }
    }
    best.map(|(j, _)| j)
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
            | Event::End { tick } => *tick,
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

#[cfg(test)]
mod tests {
    use super::*;

    /// A tick is a plain number on the wire, as before it had a type
    /// (issue 15): the same bytes both ways, and whatever a `u64` reads.
    #[test]
    fn issue_15_a_tick_reads_and_writes_as_a_plain_number() {
        for n in [0, 1, 5999, u64::MAX] {
            let t = Tick::new(n);
            assert_eq!(serde_json::to_string(&t).unwrap(), n.to_string());
            assert_eq!(serde_json::from_str::<Tick>(&n.to_string()).unwrap(), t);
            assert_eq!(
                (t.to_string(), format!("{t:?}")),
                (n.to_string(), n.to_string())
            );
        }
        for bad in ["-1", "1.5", "\"4\"", "null", "18446744073709551616"] {
            assert!(serde_json::from_str::<Tick>(bad).is_err(), "{bad}");
        }
        let e = Event::Fall {
            tick: Tick::new(7),
            robot: RobotId::from_index(2).unwrap(),
        };
        assert_eq!(
            serde_json::to_string(&e).unwrap(),
            r#"{"kind":"fall","tick":7,"robot":2}"#
        );
    }

    #[test]
    fn ticks_add_counts_and_subtract_to_counts() {
        let t = Tick::new(10);
        assert_eq!(
            (t.next(), t + 5, t - 3),
            (Tick::new(11), Tick::new(15), Tick::new(7))
        );
        assert_eq!(Tick::new(15) - t, 5);
        assert_eq!(
            (
                t.saturating_since(Tick::new(12)),
                t.saturating_since(Tick::ZERO)
            ),
            (0, 10)
        );
        assert_eq!((Tick::ZERO.prev(), t.prev()), (None, Some(Tick::new(9))));
        let mut u = t;
        u += 2;
        assert_eq!(u64::from(u), 12);
        assert_eq!(Tick::from(12), u);
        assert!(Tick::ZERO < t && t.get() == 10);
    }
}

#[cfg(test)]
mod pass_tests {
    use super::*;

    /// Player 1 at (-1, 0) facing +x, the ball at (-0.8, 0); teammates 0, 2
    /// and 3 and the opponents far off unless moved.
    fn obs() -> Observation {
        let far = |x: f32| RobotObs {
            x,
            y: -2.9,
            ..Default::default()
        };
        let mut own = [far(-4.0), far(-3.5), far(-3.0), far(-2.5)];
        own[1] = RobotObs {
            x: -1.0,
            ..Default::default()
        };
        Observation {
            tick: Tick::new(5),
            team: Team::Blue,
            player: Player::new(1).unwrap(),
            time_left: 100.0,
            score: ScoreObs::default(),
            own,
            opponents: [far(2.0), far(2.5), far(3.0), far(3.5)],
            ball: BallObs {
                x: -0.8,
                ..Default::default()
            },
            control: [false, true, false, false],
            opponent_control: false,
            reward: 0.0,
            half: 1,
            set_play: None,
        }
    }

    fn at(x: f32, y: f32) -> RobotObs {
        RobotObs {
            x,
            y,
            ..Default::default()
        }
    }

    #[test]
    fn the_most_advanced_open_teammate_in_the_cone_receives() {
        let mut o = obs();
        assert_eq!(pass_receiver(&o), None, "nobody in range");
        o.own[2] = at(0.5, 0.5);
        assert_eq!(pass_receiver(&o), Some(2));
        o.own[3] = at(1.5, -0.8);
        assert_eq!(pass_receiver(&o), Some(3), "the more advanced one");
        o.own[3].fallen = true;
        assert_eq!(pass_receiver(&o), Some(2), "a lying robot cannot receive");
        o.own[3].fallen = false;
        // An opponent on the lane to 3 (lying ones block too).
        o.opponents[0] = RobotObs {
            fallen: true,
            ..at(0.35, -0.4)
        };
        assert_eq!(pass_receiver(&o), Some(2));
    }

    #[test]
    fn distance_and_cone_limit_the_receivers() {
        let mut o = obs();
        o.own[2] = at(-0.2, 0.0); // 0.6 m from the ball: too near
        assert_eq!(pass_receiver(&o), None);
        o.own[2] = at(3.5, 0.0); // 4.3 m: too far
        assert_eq!(pass_receiver(&o), None);
        o.own[2] = at(0.2, 1.2); // atan2(1.2, 1.0) = 0.88 rad off the heading
        assert_eq!(pass_receiver(&o), None);
        o.own[1].heading = 0.5; // turned toward it
        assert_eq!(pass_receiver(&o), Some(2));
        // The kicker itself never receives, whatever its place.
        o.own[2] = at(-3.0, 2.0);
        assert_eq!(pass_receiver(&o), None);
    }

    #[test]
    fn pass_is_an_action_with_a_name() {
        assert_eq!(Action::Pass.index(), 5);
        assert_eq!(Action::from_index(5), Some(Action::Pass));
        assert_eq!("pass".parse::<Action>(), Ok(Action::Pass));
        assert_eq!(Action::PAPER.len(), 5);
        assert!(!Action::PAPER.contains(&Action::Pass));
    }
}
