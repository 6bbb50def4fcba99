//! Ids and game time: teams, robots, players, ticks, and one value per team.

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
