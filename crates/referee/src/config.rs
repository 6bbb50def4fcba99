//! The match configuration: one TOML file (`assets/match.toml`) with the
//! sections `[match]`, `[rules]`, `[reward]` and `[sim]`. Every field has the
//! paper's value (or ours, where the paper gives none) as its default, so a
//! file only needs the fields it changes.

use std::path::{Path, PathBuf};

use naosoccer_proto::PLAYERS_PER_TEAM;
use naosoccer_sim::SimConfig;
use serde::{Deserialize, Serialize};

/// Everything that decides a match, apart from the seed and the actions.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(from = "MatchConfigFile", into = "MatchConfigFile")]
pub struct MatchConfig {
    /// Physics: pitch, goals, ball, robots, gait and kick (the sim crate's own section).
    pub sim: SimConfig,
    pub rules: RulesConfig,
    pub reward: RewardConfig,
    /// Match length in minutes of game time.
    pub minutes: f32,
    /// Control ticks a second: how often every robot decides an action.
    pub control_hz: f32,
}

impl Default for MatchConfig {
    fn default() -> Self {
        MatchConfigFile::default().into()
    }
}

/// A robot's place in its team's frame (own goal at -x): x, y in metres and
/// heading in radians (0 faces the opponent goal).
pub type Placement = [f32; 3];

/// The referee's parameters.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct RulesConfig {
    /// The paper's `b_d`: a robot controls the ball only when the horizontal
    /// distance from its torso to the ball is under this (metres).
    pub b_d: f32,
    /// The paper's `b_rad`: ... and the ball lies within this angle of its
    /// heading (radians).
    pub b_rad: f32,
    /// The paper's "stand up cost": seconds a fallen robot lies before it is
    /// stood up again.
    pub standup_seconds: f32,
    /// A robot whose torso is lower than this (metres) has fallen (the paper's test).
    pub fall_height: f32,
    /// ... or whose torso tilts further than this from upright (radians).
    pub fall_tilt: f32,
    /// A set play's ball goes this far inside the line(s) it is placed on
    /// (metres): a kick-in's ball on the touch line, a corner kick's in the
    /// corner.
    pub ball_inset: f32,
    /// A robot is out when its torso is further than this outside a line (metres).
    pub robot_out_margin: f32,
    /// Where each player stands when its team kicks off (player 0 first).
    pub kickoff_attack: [Placement; PLAYERS_PER_TEAM],
    /// Where each player stands when the other team kicks off; also where a
    /// robot that left the field is reset to.
    pub kickoff_defend: [Placement; PLAYERS_PER_TEAM],
    /// Halves a match is split into, 1 or 2. With 2 the team that did not
    /// kick off the first half kicks off the second (SPL).
    pub halves: u32,
    /// Who kicks off the first half: `coin` (a coin toss seeded by the match
    /// seed), `blue` or `red`.
    pub first_kickoff: FirstKickOff,
    /// While a set play lasts, robots of the team that does not take it keep
    /// at least this far from the ball (metres; SPL: 0.75 m on its 9 m pitch).
    pub set_play_distance: f32,
    /// A set play ends when the ball has moved, or after this many seconds.
    pub set_play_seconds: f32,
    /// The goal area in front of each goal (metres): a goal kick's ball is
    /// placed on its front corner on the side where the ball left.
    pub goal_area_depth: f32,
    pub goal_area_width: f32,
    /// Whether a goal scored straight from a kick-off counts. `false` (the
    /// SPL rule until 2022): after the kick-off, a goal by the kicking team
    /// counts only once a robot other than the kicker has touched the ball;
    /// before that it is disallowed and play restarts with a goal kick for
    /// the other team. `true`: every goal counts (before protocol 1.4).
    pub direct_kick_off_goals: bool,
    /// Goals by phase: a goal counts as from the scoring team's restart when
    /// it comes at most this many seconds after the restart was awarded
    /// (and only that team touched the ball since).
    pub restart_goal_seconds: f32,
}

/// Who kicks off the first half.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum FirstKickOff {
    /// A coin toss seeded by the match seed.
    Coin,
    Blue,
    Red,
}

impl Default for RulesConfig {
    fn default() -> Self {
        RulesConfig {
            b_d: 0.3,
            b_rad: 0.4,
            standup_seconds: 5.0,
            fall_height: 0.2,
            fall_tilt: 0.5,
            ball_inset: 0.05,
            robot_out_margin: 0.3,
            kickoff_attack: [
                [-2.6, 0.0, 0.0],
                [-0.3, 0.0, 0.0],
                [-1.0, 1.2, 0.0],
                [-1.2, -1.0, 0.0],
            ],
            kickoff_defend: [
                [-2.6, 0.0, 0.0],
                [-1.0, 0.0, 0.0],
                [-1.5, 1.2, 0.0],
                [-1.8, -1.0, 0.0],
            ],
            halves: 2,
            first_kickoff: FirstKickOff::Coin,
            set_play_distance: 0.6,
            set_play_seconds: 15.0,
            goal_area_depth: 0.6,
            goal_area_width: 3.4,
            direct_kick_off_goals: false,
            restart_goal_seconds: 15.0,
        }
    }
}

/// Weights of the per-robot reward (learn's MDP):
/// `s = r_goal + r_close + r_control + r_progress`, reward `sign(s) * ln(1 + |s|)`.
/// The paper's reward has no `r_progress`; its weight is 0 by default.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct RewardConfig {
    /// Added for every robot of a team that scored this tick, subtracted when it conceded.
    pub goal: f32,
    /// Closeness to the ball: `close * exp(-distance / close_scale)`.
    pub close: f32,
    /// Metres over which closeness decays.
    pub close_scale: f32,
    /// Added to the robot that controls the ball.
    pub control: f32,
    /// Subtracted from every robot of a team whose opponent controls the ball.
    pub opponent_control: f32,
    /// Ours, not the paper's: potential-based shaping by the ball's progress,
    /// per metre, for every robot of the team. The potential is the ball's x
    /// in the team's frame (metres toward the opponent goal) and the term is
    /// `progress * (shaping_gamma * x' - x)` between the state a tick starts
    /// from and the state its physics reaches, before any restart: the
    /// jump of a restart (the ball back to the centre after a goal) is
    /// neither paid nor charged. It is added outside the log compression;
    /// 0 (off) by default.
    pub progress: f32,
    /// Ours: potential-based shaping by each robot's own distance to the
    /// ball, per metre (potential `-distance`), added to that robot's reward
    /// outside the log compression; 0 (off) by default. With `support`
    /// above 0 it pays only each team's chaser (its robot nearest the ball).
    pub approach: f32,
    /// Ours: potential-based shaping that spreads a team for passes, per
    /// metre. Every robot but its team's chaser has the potential
    /// `-support * distance` to its support spot: `support_ahead` metres
    /// ahead of the ball toward the opponent goal and `support_side` metres
    /// to the side of the ball the robot is on, kept 0.3 m inside the field.
    /// Added outside the log compression; 0 (off) by default.
    pub support: f32,
    pub support_ahead: f32,
    pub support_side: f32,
    /// How many robots of a team, besides its chaser, `support` pays: the
    /// ones nearest the ball. The rest get neither `approach` nor `support`
    /// (only `progress`). 3 (all of them) by default.
    pub support_robots: u32,
    /// The discount of the shaping terms (set it to the learner's per-tick
    /// gamma, which keeps them policy-invariant, Ng et al. 1999); 1 by default.
    pub shaping_gamma: f32,
    /// Ours: added (outside the log) to the passer and the receiver of a pass
    /// that carried the ball at least `pass_min_distance` metres and ended
    /// nearer the opponent goal than it started; 0 (off) by default. Short
    /// and backward passes earn nothing, so the bonus cannot be farmed by
    /// tapping the ball between neighbours.
    pub pass: f32,
    pub pass_min_distance: f32,
    /// Ours: added (outside the log) to a robot whose kick sends the ball
    /// at a standing teammate ahead: one within `aim_angle` radians of the
    /// ball's new direction, between `pass_min_distance` and `aim_range`
    /// metres from the ball and nearer the opponent goal than the ball. It
    /// pays the aim, not the outcome (the pass bonus pays that), so that a
    /// robot with the ball learns to turn toward a receiver before it
    /// kicks; 0 (off) by default.
    pub aim: f32,
    pub aim_angle: f32,
    pub aim_range: f32,
    /// Above 0, `aim` pays only a kick whose lane is clear: no opponent,
    /// standing or lying, within `aim_lane` metres of the straight line from
    /// the ball to the receiver. A kick at a teammate behind an opponent is
    /// a ball handed over. 0 (no lane check) by default.
    pub aim_lane: f32,
    /// Ours: charged (outside the log) every tick to a standing robot
    /// within `crowd_radius` metres of a standing teammate nearer the ball
    /// (the nearer on a tie: the lower player number). A team that swarms
    /// the ball has nobody to pass to; the team's chaser is never charged.
    /// Unlike the shaping terms this changes which policies are best. 0
    /// (off) by default. Left out of the configuration's JSON form while
    /// off (and the radius while 1 m), so configurations from before it
    /// keep their hash.
    #[serde(skip_serializing_if = "is_zero")]
    pub crowd: f32,
    #[serde(skip_serializing_if = "is_one")]
    pub crowd_radius: f32,
    /// Ours: paid (outside the log) every tick its team has the ball (a
    /// teammate controlled it when the tick started) to a standing robot,
    /// not its team's chaser, that stands ahead of the ball: at least
    /// `ahead_by` metres nearer the opponent goal than the ball and between
    /// `ahead_min` and `ahead_max` metres from it, where a kick toward the
    /// goal can find it. The potential-based `support` cannot ask for that:
    /// unlike the shaping terms this changes which policies are best. 0
    /// (off) by default, and left out of the configuration's JSON form
    /// while off (the other fields while at their defaults), so
    /// configurations from before it keep their hash.
    #[serde(skip_serializing_if = "is_zero")]
    pub ahead: f32,
    #[serde(skip_serializing_if = "is_default_ahead_by")]
    pub ahead_by: f32,
    #[serde(skip_serializing_if = "is_one")]
    pub ahead_min: f32,
    #[serde(skip_serializing_if = "is_default_ahead_max")]
    pub ahead_max: f32,
}

fn is_default_ahead_by(v: &f32) -> bool {
    *v == 0.5
}

fn is_default_ahead_max(v: &f32) -> bool {
    *v == 3.0
}

fn is_zero(v: &f32) -> bool {
    *v == 0.0
}

fn is_one(v: &f32) -> bool {
    *v == 1.0
}

impl Default for RewardConfig {
    fn default() -> Self {
        RewardConfig {
            goal: 10.0,
            close: 0.1,
            close_scale: 1.0,
            control: 0.5,
            opponent_control: 0.2,
            progress: 0.0,
            approach: 0.0,
            support: 0.0,
            support_ahead: 1.5,
            support_side: 1.0,
            support_robots: 3,
            shaping_gamma: 1.0,
            pass: 0.0,
            pass_min_distance: 1.0,
            aim: 0.0,
            aim_angle: 0.26,
            aim_range: 4.0,
            aim_lane: 0.0,
            crowd: 0.0,
            crowd_radius: 1.0,
            ahead: 0.0,
            ahead_by: 0.5,
            ahead_min: 1.0,
            ahead_max: 3.0,
        }
    }
}

/// Why a configuration was refused.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ConfigError {
    #[error("cannot read match config {path}: {source}")]
    Read {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("invalid match config: {0}")]
    Parse(#[from] toml::de::Error),
    #[error("invalid match config: `{field}` {reason}")]
    Invalid { field: &'static str, reason: String },
}

impl MatchConfig {
    /// Parses and validates a TOML configuration; missing fields take their defaults.
    pub fn from_toml_str(s: &str) -> Result<MatchConfig, ConfigError> {
        let cfg: MatchConfig = toml::from_str(s)?;
        cfg.validate()?;
        Ok(cfg)
    }

    pub fn from_file(path: &Path) -> Result<MatchConfig, ConfigError> {
        let text = std::fs::read_to_string(path).map_err(|source| ConfigError::Read {
            path: path.to_path_buf(),
            source,
        })?;
        MatchConfig::from_toml_str(&text)
    }

    /// The configuration as TOML, in the layout `from_toml_str` reads.
    pub fn to_toml_string(&self) -> String {
        // Every field is a plain number, array or table, which TOML can always hold.
        toml::to_string(self).expect("a MatchConfig is always representable in TOML")
    }

    /// Checks the ranges the referee relies on (the sim checks its own section
    /// when a `Sim` is built).
    pub fn validate(&self) -> Result<(), ConfigError> {
        fn positive(field: &'static str, v: f32) -> Result<(), ConfigError> {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                Err(ConfigError::Invalid {
                    field,
                    reason: format!("must be a positive number, got {v}"),
                })
            }
        }
        fn non_negative(field: &'static str, v: f32) -> Result<(), ConfigError> {
            if v.is_finite() && v >= 0.0 {
                Ok(())
            } else {
                Err(ConfigError::Invalid {
                    field,
                    reason: format!("must be zero or more, got {v}"),
                })
            }
        }
        positive("match.minutes", self.minutes)?;
        positive("match.control_hz", self.control_hz)?;
        let steps = crate::sim_glue::steps_per_tick(&self.sim, self.control_hz);
        let tick = 1.0 / f64::from(self.control_hz);
        let stepped = f64::from(steps) * f64::from(self.sim.dt);
        // A bad dt is the sim's to report, when the match builds its Sim.
        let dt_ok = self.sim.dt.is_finite() && self.sim.dt > 0.0;
        if dt_ok && (stepped - tick).abs() > 0.01 * tick {
            return Err(ConfigError::Invalid {
                field: "match.control_hz",
                reason: format!(
                    "must make a control tick a whole number of physics steps (sim.dt = {} s), got {} Hz",
                    self.sim.dt, self.control_hz
                ),
            });
        }
        let r = &self.rules;
        positive("rules.b_d", r.b_d)?;
        positive("rules.b_rad", r.b_rad)?;
        if r.b_rad > std::f32::consts::PI {
            return Err(ConfigError::Invalid {
                field: "rules.b_rad",
                reason: format!("must be at most pi, got {}", r.b_rad),
            });
        }
        non_negative("rules.standup_seconds", r.standup_seconds)?;
        positive("rules.fall_height", r.fall_height)?;
        positive("rules.fall_tilt", r.fall_tilt)?;
        non_negative("rules.ball_inset", r.ball_inset)?;
        if r.halves == 0 || r.halves > 2 {
            return Err(ConfigError::Invalid {
                field: "rules.halves",
                reason: format!("must be 1 or 2, got {}", r.halves),
            });
        }
        non_negative("rules.set_play_distance", r.set_play_distance)?;
        non_negative("rules.set_play_seconds", r.set_play_seconds)?;
        non_negative("rules.restart_goal_seconds", r.restart_goal_seconds)?;
        positive("rules.goal_area_depth", r.goal_area_depth)?;
        positive("rules.goal_area_width", r.goal_area_width)?;
        let (hl, hw) = (self.sim.field_length / 2.0, self.sim.field_width / 2.0);
        if r.ball_inset >= hw.min(hl) {
            return Err(ConfigError::Invalid {
                field: "rules.ball_inset",
                reason: format!("must be less than half the field, got {}", r.ball_inset),
            });
        }
        if r.goal_area_depth >= hl || r.goal_area_width / 2.0 > hw {
            return Err(ConfigError::Invalid {
                field: "rules.goal_area_depth",
                reason: format!(
                    "the goal area ({} x {} m) must fit in its half of the field",
                    r.goal_area_depth, r.goal_area_width
                ),
            });
        }
        non_negative("rules.robot_out_margin", r.robot_out_margin)?;
        for (field, places) in [
            ("rules.kickoff_attack", &r.kickoff_attack),
            ("rules.kickoff_defend", &r.kickoff_defend),
        ] {
            if places.iter().flatten().any(|v| !v.is_finite()) {
                return Err(ConfigError::Invalid {
                    field,
                    reason: "must hold finite numbers".into(),
                });
            }
        }
        let w = &self.reward;
        for (field, v) in [
            ("reward.goal", w.goal),
            ("reward.close", w.close),
            ("reward.control", w.control),
            ("reward.opponent_control", w.opponent_control),
            ("reward.progress", w.progress),
            ("reward.approach", w.approach),
            ("reward.support", w.support),
            ("reward.support_ahead", w.support_ahead),
            ("reward.support_side", w.support_side),
            ("reward.pass", w.pass),
            ("reward.pass_min_distance", w.pass_min_distance),
            ("reward.aim", w.aim),
            ("reward.aim_angle", w.aim_angle),
            ("reward.aim_range", w.aim_range),
            ("reward.aim_lane", w.aim_lane),
            ("reward.crowd", w.crowd),
            ("reward.ahead", w.ahead),
            ("reward.ahead_by", w.ahead_by),
            ("reward.ahead_min", w.ahead_min),
        ] {
            non_negative(field, v)?;
        }
        positive("reward.close_scale", w.close_scale)?;
        positive("reward.crowd_radius", w.crowd_radius)?;
        if !(w.ahead_max.is_finite() && w.ahead_max > w.ahead_min) {
            return Err(ConfigError::Invalid {
                field: "reward.ahead_max",
                reason: format!(
                    "must be a finite number above reward.ahead_min ({}), got {}",
                    w.ahead_min, w.ahead_max
                ),
            });
        }
        if !(w.shaping_gamma.is_finite() && w.shaping_gamma > 0.0 && w.shaping_gamma <= 1.0) {
            return Err(ConfigError::Invalid {
                field: "reward.shaping_gamma",
                reason: format!("must be in (0, 1], got {}", w.shaping_gamma),
            });
        }
        Ok(())
    }
}

/// The file's layout: `minutes` and `control_hz` live in a `[match]` section.
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
struct MatchConfigFile {
    #[serde(rename = "match")]
    game: MatchSection,
    rules: RulesConfig,
    reward: RewardConfig,
    sim: SimConfig,
}

#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
struct MatchSection {
    minutes: f32,
    control_hz: f32,
}

impl Default for MatchSection {
    fn default() -> Self {
        MatchSection {
            minutes: 10.0,
            control_hz: 10.0,
        }
    }
}

impl From<MatchConfigFile> for MatchConfig {
    fn from(f: MatchConfigFile) -> Self {
        MatchConfig {
            sim: f.sim,
            rules: f.rules,
            reward: f.reward,
            minutes: f.game.minutes,
            control_hz: f.game.control_hz,
        }
    }
}

impl From<MatchConfig> for MatchConfigFile {
    fn from(c: MatchConfig) -> Self {
        MatchConfigFile {
            game: MatchSection {
                minutes: c.minutes,
                control_hz: c.control_hz,
            },
            rules: c.rules,
            reward: c.reward,
            sim: c.sim,
        }
    }
}
