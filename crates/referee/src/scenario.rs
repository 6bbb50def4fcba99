//! Scenarios: a match started from a documented state instead of the
//! kick-off (docs/SCENARIOS.md is the file format's reference).
//!
//! A scenario file is written in the frame of the team under test (the
//! *own* team), which attacks +x; [`Scenario::draw`] turns it into a
//! [`Start`] in world coordinates for the colour that team plays, drawing
//! every range from a generator seeded by the match seed, and
//! [`Match::with_scenario`](crate::Match::with_scenario) puts the match
//! there. [`Judge`] decides when a scenario's play ends and with what
//! outcome.

use std::path::{Path, PathBuf};

use naosoccer_proto::{RobotId, Score, SetPlayKind, Team, Tick, PLAYERS_PER_TEAM, ROBOTS};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use serde::Deserialize;

use crate::config::MatchConfig;

mod end;
mod value;

pub use end::{EndKind, Ending, Judge};
pub use value::{Draw, Heading};

/// The draws of a scenario come from their own stream: the match seed
/// mixed with this, so the physics noise of a match is the same with or
/// without a scenario.
const STREAM: u64 = 0x5CE7_A210_D0A5_5EED;

/// Why a scenario was refused.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ScenarioError {
    #[error("cannot read scenario {path}: {source}")]
    Read {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("invalid scenario: {0}")]
    Parse(#[from] toml::de::Error),
    #[error("invalid scenario: `{field}` {reason}")]
    Invalid { field: String, reason: String },
}

fn invalid(field: impl Into<String>, reason: impl Into<String>) -> ScenarioError {
    ScenarioError::Invalid {
        field: field.into(),
        reason: reason.into(),
    }
}

/// The own team (under test, attacking +x in the file) or its opponent.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SideRef {
    Own,
    Opponent,
}

impl SideRef {
    /// The colour this side plays when the own team plays `own`.
    pub fn team(self, own: Team) -> Team {
        match self {
            SideRef::Own => own,
            SideRef::Opponent => own.other(),
        }
    }
}

/// What a scenario starts with: open play, a kick-off or a set play.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum PhaseName {
    #[default]
    OpenPlay,
    KickOff,
    KickIn,
    GoalKick,
    CornerKick,
}

impl PhaseName {
    fn set_play(self) -> Option<SetPlayKind> {
        match self {
            PhaseName::OpenPlay => None,
            PhaseName::KickOff => Some(SetPlayKind::KickOff),
            PhaseName::KickIn => Some(SetPlayKind::KickIn),
            PhaseName::GoalKick => Some(SetPlayKind::GoalKick),
            PhaseName::CornerKick => Some(SetPlayKind::CornerKick),
        }
    }
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
struct BallFile {
    x: Draw,
    y: Draw,
    #[serde(default)]
    vx: Draw,
    #[serde(default)]
    vy: Draw,
    /// Radians: robots placed from the ball, and the ball's velocity, are
    /// turned by it.
    #[serde(default)]
    direction: Draw,
}

/// Where x and y of a robot are measured from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum Origin {
    /// The centre spot (the frame's origin).
    #[default]
    Centre,
    /// The ball, where it was drawn.
    Ball,
}

/// One robot of a scenario file.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RobotSpec {
    pub side: SideRef,
    pub player: usize,
    pub x: Draw,
    pub y: Draw,
    #[serde(default)]
    pub from: Origin,
    #[serde(default)]
    pub heading: Heading,
    #[serde(default)]
    pub fallen: bool,
    #[serde(default)]
    pub busy: bool,
}

#[derive(Debug, Clone, Copy, Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct ScoreFile {
    #[serde(default)]
    own: u32,
    #[serde(default)]
    opponent: u32,
}

#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(deny_unknown_fields)]
struct TouchFile {
    side: SideRef,
    player: usize,
}

#[derive(Debug, Clone, Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct StateFile {
    #[serde(default)]
    score: ScoreFile,
    half: Option<u8>,
    elapsed: Option<f32>,
    time_left: Option<f32>,
    #[serde(default)]
    phase: PhaseName,
    taken_by: Option<SideRef>,
    last_touch: Option<TouchFile>,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
enum OutcomeName {
    Success,
    Failure,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
struct EndFile {
    when: String,
    outcome: OutcomeName,
    x: Option<[f32; 2]>,
    y: Option<[f32; 2]>,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
struct ScenarioFile {
    name: Option<String>,
    #[serde(default)]
    description: String,
    opponent: Option<String>,
    duration: Option<f32>,
    ball: Option<BallFile>,
    #[serde(default)]
    robot: Vec<RobotSpec>,
    #[serde(default)]
    state: StateFile,
    #[serde(default)]
    end: Vec<EndFile>,
}

/// The policy the opponents play where a file does not name one.
pub const DEFAULT_OPPONENT: &str = "idle";

/// A loaded, checked scenario (docs/SCENARIOS.md).
#[derive(Debug, Clone)]
pub struct Scenario {
    /// `name`, or the file's stem, or `scenario`.
    pub name: String,
    pub description: String,
    /// The team spec the opponents play in `eval`, `academy` and, unless
    /// the command line names their policy, `match`.
    pub opponent: String,
    /// Seconds of game time the play lasts at most (`None`: to the end of
    /// the match).
    pub duration: Option<f32>,
    ball: [Draw; 4],
    /// The play's direction: turns the offsets and numeric headings of
    /// robots placed from the ball, and the ball's velocity.
    direction: Draw,
    pub robots: Vec<RobotSpec>,
    score: ScoreFile,
    half: u8,
    /// Seconds into the half: elapsed (`Ok`) or left (`Err`).
    clock: Result<f32, f32>,
    phase: PhaseName,
    taken_by: Option<SideRef>,
    last_touch: Option<(SideRef, usize)>,
    pub ends: Vec<(EndKind, bool)>,
    /// The file's text, as read (what a recording stores).
    pub source: String,
}

/// One present robot of a [`Start`], world coordinates.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RobotStart {
    pub x: f32,
    pub y: f32,
    pub heading: f32,
    /// It starts lying.
    pub fallen: bool,
    /// It starts in the recovery of a kick (`busy`).
    pub busy: bool,
}

/// A scenario's start in world coordinates: what
/// [`Match::with_scenario`](crate::Match::with_scenario) applies.
#[derive(Debug, Clone, PartialEq)]
pub struct Start {
    /// The colour the own team plays.
    pub own: Team,
    pub ball: (f32, f32),
    pub ball_velocity: (f32, f32),
    /// By robot index: `None` for an absent robot.
    pub robots: [Option<RobotStart>; ROBOTS],
    pub score: Score,
    /// The tick the match starts at.
    pub tick: Tick,
    /// The set play in progress at the start and the team taking it.
    pub set_play: Option<(SetPlayKind, Team)>,
    pub last_touch: Option<RobotId>,
}

impl Scenario {
    /// Parses and checks a scenario file's text. `stem` names the scenario
    /// when the file has no `name`.
    pub fn from_toml(text: &str, stem: Option<&str>) -> Result<Scenario, ScenarioError> {
        let f: ScenarioFile = toml::from_str(text)?;
        let (ball, direction) = match &f.ball {
            Some(b) => ([b.x, b.y, b.vx, b.vy], b.direction),
            None => ([Draw::Fixed(0.0); 4], Draw::Fixed(0.0)),
        };
        for (v, field) in ball.iter().zip(["ball.x", "ball.y", "ball.vx", "ball.vy"]) {
            v.check(field)?;
        }
        direction.check("ball.direction")?;
        let mut seen = [false; ROBOTS];
        for (k, r) in f.robot.iter().enumerate() {
            let field = |name: &str| format!("robot[{k}].{name}");
            if r.player >= PLAYERS_PER_TEAM {
                return Err(invalid(
                    field("player"),
                    format!("is {}: players are 0 to {}", r.player, PLAYERS_PER_TEAM - 1),
                ));
            }
            let i = index(r.side, r.player);
            if std::mem::replace(&mut seen[i], true) {
                return Err(invalid(
                    field("player"),
                    format!("{:?} player {} is listed twice", r.side, r.player).to_lowercase(),
                ));
            }
            r.x.check(&field("x"))?;
            r.y.check(&field("y"))?;
            r.heading.check(&field("heading"))?;
        }
        let s = &f.state;
        let half = s.half.unwrap_or(1);
        if !(1..=2).contains(&half) {
            return Err(invalid("state.half", format!("is {half}: 1 or 2")));
        }
        let clock = match (s.elapsed, s.time_left) {
            (Some(_), Some(_)) => {
                return Err(invalid(
                    "state.time_left",
                    "and `state.elapsed` are both given: one or the other",
                ))
            }
            (e, None) => Ok(e.unwrap_or(0.0)),
            (None, Some(l)) => Err(l),
        };
        let (secs, field) = match clock {
            Ok(e) => (e, "state.elapsed"),
            Err(l) => (l, "state.time_left"),
        };
        if !(secs.is_finite() && secs >= 0.0) {
            return Err(invalid(field, format!("is {secs}: seconds, 0 or more")));
        }
        match (s.phase, s.taken_by) {
            (PhaseName::OpenPlay, Some(_)) => {
                return Err(invalid(
                    "state.taken_by",
                    "is for a kick-off or set play, not open play",
                ))
            }
            (p, None) if p != PhaseName::OpenPlay => {
                return Err(invalid(
                    "state.taken_by",
                    "is missing: a kick-off or set play is taken by `own` or `opponent`",
                ))
            }
            _ => {}
        }
        let last_touch = match s.last_touch {
            Some(t) if t.player >= PLAYERS_PER_TEAM || !seen[index(t.side, t.player)] => {
                return Err(invalid(
                    "state.last_touch",
                    "names a robot the file does not list (absent robots touch nothing)",
                ))
            }
            t => t.map(|t| (t.side, t.player)),
        };
        if let Some(d) = f.duration {
            if !(d.is_finite() && d > 0.0) {
                return Err(invalid("duration", format!("is {d}: seconds, more than 0")));
            }
        }
        let mut ends = Vec::with_capacity(f.end.len());
        for (k, e) in f.end.iter().enumerate() {
            let kind = EndKind::parse(&e.when, e.x, e.y)
                .map_err(|(field, reason)| invalid(format!("end[{k}].{field}"), reason))?;
            ends.push((kind, e.outcome == OutcomeName::Success));
        }
        let name = f
            .name
            .clone()
            .or_else(|| stem.map(str::to_owned))
            .unwrap_or_else(|| "scenario".to_owned());
        let opponent = f
            .opponent
            .clone()
            .unwrap_or_else(|| DEFAULT_OPPONENT.into());
        if opponent.trim().is_empty() {
            return Err(invalid(
                "opponent",
                "is empty: a team spec such as idle or scripted",
            ));
        }
        Ok(Scenario {
            name,
            description: f.description,
            opponent,
            duration: f.duration,
            ball,
            direction,
            robots: f.robot,
            score: s.score,
            half,
            clock,
            phase: s.phase,
            taken_by: s.taken_by,
            last_touch,
            ends,
            source: text.to_owned(),
        })
    }

    /// Reads and checks a scenario file.
    pub fn from_file(path: &Path) -> Result<Scenario, ScenarioError> {
        let text = std::fs::read_to_string(path).map_err(|source| ScenarioError::Read {
            path: path.to_owned(),
            source,
        })?;
        let stem = path.file_stem().and_then(|s| s.to_str());
        Scenario::from_toml(&text, stem)
    }

    /// Checks the scenario against a match configuration: the ball within
    /// the field lines, robots placed from the centre within the lines plus
    /// half the ground margin, the half and its clock within the match.
    pub fn check(&self, cfg: &MatchConfig) -> Result<(), ScenarioError> {
        let (hx, hy) = (cfg.sim.field_length / 2.0, cfg.sim.field_width / 2.0);
        let inside = |d: &Draw, half: f32, field: String, what: &str| {
            let (lo, hi) = d.bounds();
            if lo < -half || hi > half {
                let v = if lo < -half { lo } else { hi };
                return Err(invalid(
                    field,
                    format!("reaches {v}: {what}, within +-{half} m"),
                ));
            }
            Ok(())
        };
        let ball = "the ball starts within the field lines";
        inside(&self.ball[0], hx, "ball.x".into(), ball)?;
        inside(&self.ball[1], hy, "ball.y".into(), ball)?;
        let m = cfg.sim.ground_margin / 2.0;
        let robot = "a robot starts within the field lines plus half the ground margin";
        for (k, r) in self.robots.iter().enumerate() {
            if r.fallen && r.busy {
                return Err(invalid(
                    format!("robot[{k}].busy"),
                    "is true for a fallen robot: a robot lying on the pitch is not in a kick"
                        .to_string(),
                ));
            }
            if r.from == Origin::Centre {
                inside(&r.x, hx + m, format!("robot[{k}].x"), robot)?;
                inside(&r.y, hy + m, format!("robot[{k}].y"), robot)?;
            }
        }
        let clock = crate::rules::Clock::new(cfg.minutes, cfg.control_hz, cfg.rules.halves);
        let Some((first, end)) = clock.half_span(self.half) else {
            return Err(invalid(
                "state.half",
                "is 2, but the match configuration plays one half",
            ));
        };
        let ticks = end.get() - first.get();
        let (secs, field) = match self.clock {
            Ok(e) => (e, "state.elapsed"),
            Err(l) => (l, "state.time_left"),
        };
        let n = secs_to_ticks(secs, cfg);
        // At least one tick of the half is left to play.
        let fits = match self.clock {
            Ok(_) => n < ticks,
            Err(_) => (1..=ticks).contains(&n),
        };
        if !fits {
            return Err(invalid(
                field,
                format!(
                    "is {secs} s: at least one tick of the half's {} s must be left to play",
                    ticks as f32 / cfg.control_hz
                ),
            ));
        }
        Ok(())
    }

    /// The start for the own team playing `own` in a match of `seed`:
    /// every range drawn (ball x, y, vx, vy, direction, then each robot's x, y and
    /// heading in file order) from a ChaCha8 generator seeded by the
    /// match seed, and the file's frame turned into the world's. Call
    /// [`Scenario::check`] first.
    pub fn draw(&self, cfg: &MatchConfig, seed: u64, own: Team) -> Start {
        let mut rng = ChaCha8Rng::seed_from_u64(seed ^ STREAM);
        let [bx, by, vx, vy] = self.ball.map(|d| d.draw(&mut rng));
        // The play's direction (none: 0, and nothing drawn).
        let dir = self.direction.draw(&mut rng);
        let (sin, cos) = dir.sin_cos();
        let turned = |x: f32, y: f32| (x * cos - y * sin, x * sin + y * cos);
        let (vx, vy) = turned(vx, vy);
        // The file's frame to the world's: red sees the world turned.
        let (sign, turn) = match own {
            Team::Blue => (1.0, 0.0),
            Team::Red => (-1.0, std::f32::consts::PI),
        };
        let goal_x = cfg.sim.field_length / 2.0;
        let mut robots = [None; ROBOTS];
        for r in &self.robots {
            let (dx, dy) = (r.x.draw(&mut rng), r.y.draw(&mut rng));
            let (x, y) = match r.from {
                Origin::Centre => (dx, dy),
                Origin::Ball => {
                    let (tx, ty) = turned(dx, dy);
                    (bx + tx, by + ty)
                }
            };
            let h = match r.heading {
                Heading::Angle(d) if r.from == Origin::Ball => d.draw(&mut rng) + dir,
                Heading::Angle(d) => d.draw(&mut rng),
                Heading::Ball => (by - y).atan2(bx - x),
                // The goal its own team attacks: +x for the own team.
                Heading::Goal => match r.side {
                    SideRef::Own => (0.0 - y).atan2(goal_x - x),
                    SideRef::Opponent => (0.0 - y).atan2(-goal_x - x),
                },
            };
            let i = r.side.team(own).index() * PLAYERS_PER_TEAM + r.player;
            robots[i] = Some(RobotStart {
                x: sign * x,
                y: sign * y,
                heading: crate::rules::wrap_angle(h + turn),
                fallen: r.fallen,
                busy: r.busy,
            });
        }
        let clock = crate::rules::Clock::new(cfg.minutes, cfg.control_hz, cfg.rules.halves);
        let (first, end) = clock
            .half_span(self.half)
            .expect("Scenario::check keeps the half within the match");
        let tick = match self.clock {
            Ok(e) => first + secs_to_ticks(e, cfg),
            Err(l) => Tick::new(end.get().saturating_sub(secs_to_ticks(l, cfg))),
        };
        let mut score = Score::default();
        *score.get_mut(own) = self.score.own;
        *score.get_mut(own.other()) = self.score.opponent;
        Start {
            own,
            ball: (sign * bx, sign * by),
            ball_velocity: (sign * vx, sign * vy),
            robots,
            score,
            tick,
            set_play: self
                .phase
                .set_play()
                .zip(self.taken_by)
                .map(|(k, side)| (k, side.team(own))),
            last_touch: self
                .last_touch
                .and_then(|(side, p)| RobotId::new(side.team(own), p)),
        }
    }

    /// The judge of this scenario's play for the own team playing `own`,
    /// from the start tick `start`.
    pub fn judge(&self, cfg: &MatchConfig, own: Team, start: Tick) -> Judge {
        let limit = self.duration.map(|d| secs_to_ticks(d, cfg).max(1));
        Judge::new(own, start, limit, self.ends.clone())
    }
}

/// `side`'s `player` among the eight, the own team first (a file's own
/// order, whatever colour the own team plays).
fn index(side: SideRef, player: usize) -> usize {
    match side {
        SideRef::Own => player,
        SideRef::Opponent => PLAYERS_PER_TEAM + player,
    }
}

fn secs_to_ticks(secs: f32, cfg: &MatchConfig) -> u64 {
    (f64::from(secs) * f64::from(cfg.control_hz)).round() as u64
}

#[cfg(test)]
mod tests;
