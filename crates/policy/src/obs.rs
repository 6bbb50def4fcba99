//! The observation vector: `proto::Observation` flattened into the fixed f32
//! layout the networks read. Versioned: a checkpoint records the version it
//! was trained on and refuses to load under a version this build cannot
//! encode. docs/LEARNING.md lists both layouts; a test checks they agree.
//!
//! - Version 4 ([`OBS_DIM`] = 92 entries): version 3, then what a shot
//!   needs: how clear the lane is from the ball along the acting robot's
//!   heading (where its kick goes) and from the ball to the goal's centre,
//!   and where that heading meets the goal line.
//! - Version 3 (89 entries): version 2, then what a pass
//!   needs seen from the acting robot: each teammate ahead of and beside it
//!   (where a kick goes), whether that teammate faces the ball, how clear
//!   the lane from the ball to it is, and the nearest opponent.
//! - Version 2 (the default for new runs, 75 entries): egocentric first. The
//!   acting robot, then the ball seen from it at kick-reach resolution, the
//!   two goals seen from it, the ball, the other three teammates, the
//!   opponents, and the game state (clock, half, score, set play, role).
//! - Version 1 (48 entries, the shipped `paper`/`cleanrl`/DQN teams): the
//!   paper's state in the team frame. Still encoded so those teams play.
//!
//! Rows are always [`OBS_DIM`] wide; a narrower layout fills a prefix and
//! zeroes the rest, and its networks read the prefix ([`ObsScale::dim`]).
//!
//! Everything is computed from the `proto::Observation` alone, so a robot
//! playing over the socket sees exactly what it saw in training. Positions
//! are in the acting team's frame (the referee mirrors red's view, so a team
//! always attacks +x).

use naosoccer_proto::{Observation, RobotObs, PLAYERS_PER_TEAM};
use naosoccer_referee::rules::segment_distance;
use serde::{Deserialize, Serialize};

/// The layout new runs are trained on unless they choose another
/// (`train --obs-version`).
pub const OBS_VERSION: u32 = 2;

/// The newest layout this build encodes.
pub const OBS_VERSION_LATEST: u32 = 4;

/// Row width of observation buffers: the widest layout's length (version 4).
pub const OBS_DIM: usize = 92;

/// Length of layout version 3.
pub const OBS_DIM_V3: usize = 89;

/// Length of layout version 2.
pub const OBS_DIM_V2: usize = 75;

/// Length of layout version 1.
pub const OBS_DIM_V1: usize = 48;

/// Ball speeds are divided by this (m/s): a hard kick is a few m/s.
pub const BALL_SPEED_SCALE: f32 = 2.0;

/// The ball in the robot frame (`ball_ahead`, `ball_side`) is divided by this
/// (metres) and clamped to +-[`NEAR_CLAMP`]: 1 cm is 0.04 input units.
pub const NEAR_SCALE: f32 = 0.25;
pub const NEAR_CLAMP: f32 = 4.0;

/// Set-play ticks left are divided by this.
pub const SET_PLAY_TICKS_SCALE: f32 = 100.0;

/// A pass lane's clearance (the nearest opponent's distance from the
/// segment ball to teammate) is divided by this (metres) and clamped to 1.
pub const LANE_SCALE: f32 = 1.0;

/// Where a heading that misses the goal line is put in `shot_aim`, and the
/// clamp of that entry (goal half widths).
pub const AIM_CLAMP: f32 = 3.0;

/// The entries of layout version 4, in order, as docs/LEARNING.md lists them:
/// version 3's, then these.
#[rustfmt::skip]
pub const FEATURE_NAMES_V4_TAIL: [&str; OBS_DIM - OBS_DIM_V3] = [
    "shot_lane", "goal_lane", "shot_aim",
];

/// The entries of layout version 3, in order, as docs/LEARNING.md lists them:
/// version 2's, then these.
#[rustfmt::skip]
pub const FEATURE_NAMES_V3_TAIL: [&str; OBS_DIM_V3 - OBS_DIM_V2] = [
    "mate1_ahead", "mate1_side", "mate1_faces_ball", "mate1_lane",
    "mate2_ahead", "mate2_side", "mate2_faces_ball", "mate2_lane",
    "mate3_ahead", "mate3_side", "mate3_faces_ball", "mate3_lane",
    "opp_near_ahead", "opp_near_side",
];

/// The entries of layout version 2, in order, as docs/LEARNING.md lists them.
#[rustfmt::skip]
pub const FEATURE_NAMES: [&str; OBS_DIM_V2] = [
    "me_x", "me_y", "me_cos", "me_sin", "me_fallen", "me_busy", "me_control",
    "ball_dist", "ball_cos", "ball_sin", "ball_ahead", "ball_side", "ball_in_reach",
    "goal_dist", "goal_cos", "goal_sin", "own_goal_dist", "own_goal_cos", "own_goal_sin",
    "ball_x", "ball_y", "ball_vx", "ball_vy",
    "mate1_x", "mate1_y", "mate1_cos", "mate1_sin", "mate1_fallen", "mate1_control",
    "mate2_x", "mate2_y", "mate2_cos", "mate2_sin", "mate2_fallen", "mate2_control",
    "mate3_x", "mate3_y", "mate3_cos", "mate3_sin", "mate3_fallen", "mate3_control",
    "opp0_x", "opp0_y", "opp0_cos", "opp0_sin", "opp0_fallen",
    "opp1_x", "opp1_y", "opp1_cos", "opp1_sin", "opp1_fallen",
    "opp2_x", "opp2_y", "opp2_cos", "opp2_sin", "opp2_fallen",
    "opp3_x", "opp3_y", "opp3_cos", "opp3_sin", "opp3_fallen",
    "opp_control",
    "time_left", "second_half", "score_diff",
    "sp_kick_off", "sp_kick_in", "sp_goal_kick", "sp_corner_kick", "sp_own", "sp_ticks_left",
    "me0", "me1", "me2", "me3",
];

/// The entries of layout version 1, in order.
#[rustfmt::skip]
pub const FEATURE_NAMES_V1: [&str; OBS_DIM_V1] = [
    "own0_x", "own0_y", "own0_cos", "own0_sin",
    "own1_x", "own1_y", "own1_cos", "own1_sin",
    "own2_x", "own2_y", "own2_cos", "own2_sin",
    "own3_x", "own3_y", "own3_cos", "own3_sin",
    "ball_x", "ball_y", "ball_vx", "ball_vy",
    "ifc0", "ifc1", "ifc2", "ifc3",
    "opp0_x", "opp0_y", "opp0_cos", "opp0_sin",
    "opp1_x", "opp1_y", "opp1_cos", "opp1_sin",
    "opp2_x", "opp2_y", "opp2_cos", "opp2_sin",
    "opp3_x", "opp3_y", "opp3_cos", "opp3_sin",
    "me0", "me1", "me2", "me3",
    "opp_control",
    "ball_fwd", "ball_left",
    "me_fallen",
];

/// The layout length of `version`, `None` for a version this build cannot encode.
pub fn layout_dim(version: u32) -> Option<usize> {
    match version {
        1 => Some(OBS_DIM_V1),
        2 => Some(OBS_DIM_V2),
        3 => Some(OBS_DIM_V3),
        4 => Some(OBS_DIM),
        _ => None,
    }
}

fn one() -> u32 {
    1
}

/// Where a kick reaches (the sim's `kick_reach_min/max`, `kick_half_width`,
/// metres): the ball centre must lie this far ahead of the robot's origin
/// and within the half width to either side.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct KickReach {
    pub min: f32,
    pub max: f32,
    pub half_width: f32,
}

impl Default for KickReach {
    fn default() -> KickReach {
        let s = naosoccer_referee::MatchConfig::default().sim;
        KickReach {
            min: s.kick_reach_min,
            max: s.kick_reach_max,
            half_width: s.kick_half_width,
        }
    }
}

impl KickReach {
    /// Whether a ball `ahead` metres in front and `side` to the left is in reach.
    pub fn contains(&self, ahead: f32, side: f32) -> bool {
        ahead >= self.min && ahead <= self.max && side.abs() <= self.half_width
    }

    /// Whether the robot that received `obs` has the ball in kick reach.
    pub fn in_reach(&self, obs: &Observation) -> bool {
        let (ahead, side) = ball_in_robot_frame(obs);
        self.contains(ahead, side)
    }
}

fn default_match_seconds() -> f32 {
    600.0
}

fn default_goal_half_width() -> f32 {
    naosoccer_referee::MatchConfig::default().sim.goal_width * 0.5
}

/// The ball relative to the robot that received `obs`: metres ahead along
/// its heading and to its left.
pub fn ball_in_robot_frame(obs: &Observation) -> (f32, f32) {
    let r = obs.me();
    let (dx, dy) = (obs.ball.x - r.x, obs.ball.y - r.y);
    let (s, c) = r.heading.sin_cos();
    (c * dx + s * dy, -s * dx + c * dy)
}

/// How observations are encoded: the layout version and the scales it uses.
/// Stored in every checkpoint's configuration, so a policy encodes as it was
/// trained. (Configurations written before version 2 hold only the half
/// sizes; the other fields then take their defaults.)
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ObsScale {
    pub half_length: f32,
    pub half_width: f32,
    /// Layout version; set from the run's `obs_version` when loading.
    #[serde(default = "one")]
    pub version: u32,
    #[serde(default)]
    pub kick: KickReach,
    /// The match length, seconds (`time_left` is divided by it).
    #[serde(default = "default_match_seconds")]
    pub match_seconds: f32,
    /// Half the goal's width, metres (version 4's `shot_aim` is divided by it).
    #[serde(default = "default_goal_half_width")]
    pub goal_half_width: f32,
}

impl ObsScale {
    /// The current layout for matches configured as `cfg`.
    pub fn from_config(cfg: &naosoccer_referee::MatchConfig) -> ObsScale {
        let f = naosoccer_referee::Field::from_sim(&cfg.sim);
        ObsScale {
            half_length: f.half_length,
            half_width: f.half_width,
            version: OBS_VERSION,
            kick: KickReach {
                min: cfg.sim.kick_reach_min,
                max: cfg.sim.kick_reach_max,
                half_width: cfg.sim.kick_half_width,
            },
            match_seconds: (cfg.minutes * 60.0).max(1e-3),
            goal_half_width: cfg.sim.goal_width * 0.5,
        }
    }

    /// This layout's length (the prefix of each row the networks read).
    pub fn dim(&self) -> usize {
        layout_dim(self.version).unwrap_or(OBS_DIM)
    }

    /// Writes the observation vector for the robot that received `obs` into
    /// `out` (length [`OBS_DIM`]; a shorter layout zeroes the tail).
    /// Allocation-free: training calls this for every robot every tick.
    pub fn encode(&self, obs: &Observation, out: &mut [f32]) {
        assert_eq!(
            out.len(),
            OBS_DIM,
            "observation buffer must hold OBS_DIM values"
        );
        match self.version {
            1 => {
                self.encode_v1(obs, &mut out[..OBS_DIM_V1]);
                out[OBS_DIM_V1..].fill(0.0);
            }
            2 => {
                self.encode_v2(obs, &mut out[..OBS_DIM_V2]);
                out[OBS_DIM_V2..].fill(0.0);
            }
            3 => {
                self.encode_v2(obs, &mut out[..OBS_DIM_V2]);
                self.encode_v3_tail(obs, &mut out[OBS_DIM_V2..OBS_DIM_V3]);
                out[OBS_DIM_V3..].fill(0.0);
            }
            _ => {
                self.encode_v2(obs, &mut out[..OBS_DIM_V2]);
                self.encode_v3_tail(obs, &mut out[OBS_DIM_V2..OBS_DIM_V3]);
                self.encode_v4_tail(obs, &mut out[OBS_DIM_V3..]);
            }
        }
    }

    /// Version 4's entries after version 3's: the shot picture. A kick
    /// goes from the ball along the kicker's heading, so the lane that
    /// matters is the segment from the ball that way, as long as the ball's
    /// distance to the goal's centre; an opponent near it takes the shot.
    fn encode_v4_tail(&self, obs: &Observation, out: &mut [f32]) {
        let r = obs.me();
        let (s, c) = r.heading.sin_cos();
        let ball = [obs.ball.x, obs.ball.y];
        let goal = [self.half_length, 0.0];
        let (gx, gy) = (goal[0] - ball[0], goal[1] - ball[1]);
        let reach = (gx * gx + gy * gy).sqrt();
        let end = [ball[0] + c * reach, ball[1] + s * reach];
        let clearance = |to: [f32; 2]| {
            let d = obs
                .opponents
                .iter()
                .filter(|o| !o.fallen)
                .map(|o| segment_distance(ball, to, [o.x, o.y]))
                .fold(f32::INFINITY, f32::min);
            (d / LANE_SCALE).min(1.0)
        };
        out[0] = clearance(end);
        out[1] = clearance(goal);
        // Where the heading line from the ball meets the goal line, in goal
        // half widths: within +-1 the kick goes between the posts.
        out[2] = if c > 1e-3 {
            let y = ball[1] + gx * s / c;
            (y / self.goal_half_width).clamp(-AIM_CLAMP, AIM_CLAMP)
        } else if s < 0.0 {
            -AIM_CLAMP
        } else {
            AIM_CLAMP
        };
    }

    /// Version 3's entries after version 2's: the pass picture from the
    /// acting robot. A kick goes along its heading, so a teammate far ahead
    /// and little to the side is one a kick reaches.
    fn encode_v3_tail(&self, obs: &Observation, out: &mut [f32]) {
        let sx = 1.0 / self.half_length;
        let me = obs.player.index();
        let r = obs.me();
        let (s, c) = r.heading.sin_cos();
        let local = |x: f32, y: f32| {
            let (dx, dy) = (x - r.x, y - r.y);
            (c * dx + s * dy, -s * dx + c * dy)
        };
        let (bx, by) = (obs.ball.x, obs.ball.y);
        let mut i = 0;
        for p in (0..PLAYERS_PER_TEAM).filter(|&p| p != me) {
            let m = &obs.own[p];
            let (ahead, side) = local(m.x, m.y);
            out[i] = ahead * sx;
            out[i + 1] = side * sx;
            // Cosine between the teammate's heading and its direction to the ball.
            let (dx, dy) = (bx - m.x, by - m.y);
            let d = (dx * dx + dy * dy).sqrt();
            out[i + 2] = if d < 1e-6 {
                1.0
            } else {
                (m.heading.cos() * dx + m.heading.sin() * dy) / d
            };
            let clear = obs
                .opponents
                .iter()
                .filter(|o| !o.fallen)
                .map(|o| segment_distance([bx, by], [m.x, m.y], [o.x, o.y]))
                .fold(f32::INFINITY, f32::min);
            out[i + 3] = (clear / LANE_SCALE).min(1.0);
            i += 4;
        }
        let mut nearest = (f32::INFINITY, 0.0, 0.0);
        for o in &obs.opponents {
            let (ahead, side) = local(o.x, o.y);
            let d = ahead * ahead + side * side;
            if d < nearest.0 {
                nearest = (d, ahead, side);
            }
        }
        out[i] = nearest.1 * sx;
        out[i + 1] = nearest.2 * sx;
    }

    fn encode_v2(&self, obs: &Observation, out: &mut [f32]) {
        let (sx, sy) = (1.0 / self.half_length, 1.0 / self.half_width);
        let me = obs.player.index();
        let r = obs.me();
        let (s, c) = r.heading.sin_cos();
        let flag = |b: bool| f32::from(u8::from(b));
        // Distance and bearing (cos, sin relative to the heading) of a point.
        let seen = |x: f32, y: f32| -> (f32, f32, f32) {
            let (dx, dy) = (x - r.x, y - r.y);
            let d = (dx * dx + dy * dy).sqrt();
            if d < 1e-6 {
                return (0.0, 1.0, 0.0);
            }
            let (fwd, left) = (c * dx + s * dy, -s * dx + c * dy);
            (d, fwd / d, left / d)
        };
        out[0] = r.x * sx;
        out[1] = r.y * sy;
        out[2] = c;
        out[3] = s;
        out[4] = flag(r.fallen);
        out[5] = flag(r.busy);
        out[6] = flag(obs.control[me]);
        let (d, bc, bs) = seen(obs.ball.x, obs.ball.y);
        let (ahead, side) = ball_in_robot_frame(obs);
        out[7] = d * sx;
        out[8] = bc;
        out[9] = bs;
        out[10] = (ahead / NEAR_SCALE).clamp(-NEAR_CLAMP, NEAR_CLAMP);
        out[11] = (side / NEAR_SCALE).clamp(-NEAR_CLAMP, NEAR_CLAMP);
        out[12] = flag(self.kick.contains(ahead, side));
        let (d, gc, gs) = seen(self.half_length, 0.0);
        out[13] = d * sx * 0.5;
        out[14] = gc;
        out[15] = gs;
        let (d, gc, gs) = seen(-self.half_length, 0.0);
        out[16] = d * sx * 0.5;
        out[17] = gc;
        out[18] = gs;
        out[19] = obs.ball.x * sx;
        out[20] = obs.ball.y * sy;
        out[21] = obs.ball.vx / BALL_SPEED_SCALE;
        out[22] = obs.ball.vy / BALL_SPEED_SCALE;
        let mut i = 23;
        for p in (0..PLAYERS_PER_TEAM).filter(|&p| p != me) {
            let m = &obs.own[p];
            out[i] = m.x * sx;
            out[i + 1] = m.y * sy;
            out[i + 2] = m.heading.cos();
            out[i + 3] = m.heading.sin();
            out[i + 4] = flag(m.fallen);
            out[i + 5] = flag(obs.control[p]);
            i += 6;
        }
        for o in &obs.opponents {
            out[i] = o.x * sx;
            out[i + 1] = o.y * sy;
            out[i + 2] = o.heading.cos();
            out[i + 3] = o.heading.sin();
            out[i + 4] = flag(o.fallen);
            i += 5;
        }
        out[61] = flag(obs.opponent_control);
        out[62] = (obs.time_left / self.match_seconds).clamp(0.0, 1.0);
        out[63] = flag(obs.half >= 2);
        let diff = obs.score.own as f32 - obs.score.opponent as f32;
        out[64] = (diff / 2.0).tanh();
        out[65..71].fill(0.0);
        if let Some(sp) = &obs.set_play {
            out[65 + sp.kind.index()] = 1.0;
            out[69] = flag(sp.own);
            out[70] = (sp.ticks_left as f32 / SET_PLAY_TICKS_SCALE).min(1.0);
        }
        for p in 0..PLAYERS_PER_TEAM {
            out[71 + p] = flag(p == me);
        }
    }

    fn encode_v1(&self, obs: &Observation, out: &mut [f32]) {
        let (sx, sy) = (1.0 / self.half_length, 1.0 / self.half_width);
        let robot = |r: &RobotObs, dst: &mut [f32]| {
            dst[0] = r.x * sx;
            dst[1] = r.y * sy;
            dst[2] = r.heading.cos();
            dst[3] = r.heading.sin();
        };
        for p in 0..PLAYERS_PER_TEAM {
            robot(&obs.own[p], &mut out[4 * p..4 * p + 4]);
            robot(&obs.opponents[p], &mut out[24 + 4 * p..28 + 4 * p]);
            out[20 + p] = f32::from(u8::from(obs.control[p]));
        }
        out[16] = obs.ball.x * sx;
        out[17] = obs.ball.y * sy;
        out[18] = obs.ball.vx / BALL_SPEED_SCALE;
        out[19] = obs.ball.vy / BALL_SPEED_SCALE;
        let me = obs.player.index();
        for p in 0..PLAYERS_PER_TEAM {
            out[40 + p] = if p == me { 1.0 } else { 0.0 };
        }
        out[44] = f32::from(u8::from(obs.opponent_control));
        // The ball seen from the acting robot (forward, left), which the
        // rotation decisions hinge on; the network could derive it, but only
        // through a product of inputs that small MLPs learn slowly.
        let (fwd, left) = ball_in_robot_frame(obs);
        out[45] = fwd * sx;
        out[46] = left * sx;
        out[47] = f32::from(u8::from(obs.me().fallen));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use naosoccer_proto::Tick;
    use naosoccer_proto::{BallObs, ScoreObs, Team};

    /// The guide, where the layouts in use are documented.
    const GUIDE: &str = include_str!("../../../docs/LEARNING.md");
    /// The paper-era layout (version 1), documented with the paper's reproduction.
    const PAPER: &str = include_str!("../../../docs/experiments/2026-11-22-paper-reproduction.md");

    /// An observation-layout table of a document: rows `| index | name | ... |`
    /// between the markers `<!-- TAG:begin -->` and `<!-- TAG:end -->`.
    fn documented_layout(doc: &str, tag: &str) -> Vec<(usize, String)> {
        let start = doc
            .find(&format!("<!-- {tag}:begin -->"))
            .expect("layout start marker in the document");
        let end = doc
            .find(&format!("<!-- {tag}:end -->"))
            .expect("layout end marker in the document");
        doc[start..end]
            .lines()
            .filter_map(|l| {
                let cells: Vec<&str> = l.split('|').map(str::trim).collect();
                let index = cells.get(1)?.parse::<usize>().ok()?;
                Some((index, cells.get(2)?.trim_matches('`').to_string()))
            })
            .collect()
    }

    #[test]
    fn layouts_match_their_documentation() {
        for (doc, tag, names, first) in [
            (GUIDE, "obs-layout", &FEATURE_NAMES[..], 0),
            (PAPER, "obs-layout-v1", &FEATURE_NAMES_V1[..], 0),
            (
                GUIDE,
                "obs-layout-v3",
                &FEATURE_NAMES_V3_TAIL[..],
                OBS_DIM_V2,
            ),
            (
                GUIDE,
                "obs-layout-v4",
                &FEATURE_NAMES_V4_TAIL[..],
                OBS_DIM_V3,
            ),
        ] {
            let doc = documented_layout(doc, tag);
            assert_eq!(
                doc.len(),
                names.len(),
                "the documentation lists every entry of {tag} once"
            );
            for (i, (index, name)) in doc.iter().enumerate() {
                assert_eq!(*index, first + i, "{tag}: entries in order");
                assert_eq!(name, names[i], "{tag}: entry {i}");
            }
        }
        assert_eq!(layout_dim(OBS_VERSION), Some(OBS_DIM_V2));
        assert_eq!(layout_dim(OBS_VERSION_LATEST), Some(OBS_DIM));
        assert!(
            GUIDE.contains(&format!("version {OBS_VERSION}")),
            "docs name the layout version"
        );
    }

    fn named(v: &[f32], name: &str) -> f32 {
        v[FEATURE_NAMES_V1.iter().position(|n| *n == name).unwrap()]
    }

    fn named2(v: &[f32], name: &str) -> f32 {
        let all = FEATURE_NAMES
            .iter()
            .chain(&FEATURE_NAMES_V3_TAIL)
            .chain(&FEATURE_NAMES_V4_TAIL);
        v[all.clone().position(|n| *n == name).unwrap()]
    }

    fn test_scale(version: u32) -> ObsScale {
        ObsScale {
            half_length: 3.0,
            half_width: 2.25,
            version,
            kick: KickReach {
                min: 0.1,
                max: 0.26,
                half_width: 0.11,
            },
            match_seconds: 600.0,
            goal_half_width: 1.3,
        }
    }

    fn sample_observation() -> Observation {
        let robot = |x: f32, y: f32, heading: f32, fallen: bool| RobotObs {
            x,
            y,
            heading,
            fallen,
            busy: false,
        };
        Observation {
            tick: Tick::new(7),
            team: Team::Red,
            player: naosoccer_proto::Player::new(2).unwrap(),
            time_left: 100.0,
            score: ScoreObs {
                own: 1,
                opponent: 0,
            },
            own: [
                robot(-2.7, 0.0, 0.0, false),
                robot(-1.5, 1.125, std::f32::consts::FRAC_PI_2, false),
                robot(1.0, -1.0, std::f32::consts::PI, true),
                robot(0.0, 0.0, 0.0, false),
            ],
            opponents: [
                robot(3.0, 2.25, 0.0, false),
                robot(0.0, 0.0, 0.0, false),
                robot(0.0, 0.0, 0.0, false),
                robot(-0.3, -0.45, -std::f32::consts::FRAC_PI_2, false),
            ],
            ball: BallObs {
                x: 0.0,
                y: -1.0,
                vx: 1.0,
                vy: -0.5,
            },
            control: [false, false, true, false],
            opponent_control: false,
            reward: 0.0,
            half: 1,
            set_play: None,
        }
    }

    #[test]
    fn version_1_encoding_puts_each_quantity_where_documented() {
        let scale = test_scale(1);
        let obs = sample_observation();
        let mut v = [0.0; OBS_DIM];
        scale.encode(&obs, &mut v);
        let close = |a: f32, b: f32| (a - b).abs() < 1e-5;
        assert!(close(named(&v, "own0_x"), -0.9));
        assert!(close(named(&v, "own1_y"), 0.5));
        assert!(close(named(&v, "own1_cos"), 0.0) && close(named(&v, "own1_sin"), 1.0));
        assert!(close(named(&v, "own2_cos"), -1.0));
        assert!(close(named(&v, "opp0_x"), 1.0) && close(named(&v, "opp0_y"), 1.0));
        assert!(close(named(&v, "opp3_sin"), -1.0) && close(named(&v, "opp3_y"), -0.2));
        assert!(close(named(&v, "ball_y"), -1.0 / 2.25));
        assert!(close(named(&v, "ball_vx"), 0.5) && close(named(&v, "ball_vy"), -0.25));
        assert_eq!([named(&v, "ifc0"), named(&v, "ifc2")], [0.0, 1.0]);
        assert_eq!(
            [
                named(&v, "me0"),
                named(&v, "me1"),
                named(&v, "me2"),
                named(&v, "me3")
            ],
            [0.0, 0.0, 1.0, 0.0]
        );
        assert_eq!(named(&v, "opp_control"), 0.0);
        // Player 2 stands at (1, -1) facing -x; the ball at (0, -1) is 1 m
        // straight ahead of it.
        assert!(
            close(named(&v, "ball_fwd"), 1.0 / 3.0),
            "{}",
            named(&v, "ball_fwd")
        );
        assert!(close(named(&v, "ball_left"), 0.0));
        assert_eq!(named(&v, "me_fallen"), 1.0);
    }

    #[test]
    fn version_1_rows_zero_the_tail() {
        let mut v = [7.0; OBS_DIM];
        test_scale(1).encode(&sample_observation(), &mut v);
        assert!(v[OBS_DIM_V1..].iter().all(|&x| x == 0.0));
        assert_eq!(test_scale(1).dim(), OBS_DIM_V1);
    }

    #[test]
    fn version_2_encoding_puts_each_quantity_where_documented() {
        use naosoccer_proto::{SetPlayKind, SetPlayObs};
        let scale = test_scale(2);
        let mut obs = sample_observation();
        // Player 2 at (1, -1) facing -x, busy; the ball 20 cm ahead of it and
        // 5 cm to its left (its left is -y): in kick reach.
        obs.own[2].busy = true;
        obs.ball.x = 0.8;
        obs.ball.y = -0.95;
        obs.half = 2;
        obs.score = ScoreObs {
            own: 1,
            opponent: 3,
        };
        obs.set_play = Some(SetPlayObs {
            kind: SetPlayKind::GoalKick,
            own: true,
            ticks_left: 50,
        });
        let mut v = [0.0; OBS_DIM];
        scale.encode(&obs, &mut v);
        let n = |name: &str| named2(&v, name);
        let close = |a: f32, b: f32| (a - b).abs() < 1e-5;
        assert!(close(n("me_x"), 1.0 / 3.0) && close(n("me_y"), -1.0 / 2.25));
        assert!(close(n("me_cos"), -1.0));
        assert_eq!([n("me_fallen"), n("me_busy"), n("me_control")], [1.0; 3]);
        let d = (0.2f32 * 0.2 + 0.05 * 0.05).sqrt();
        assert!(close(n("ball_dist"), d / 3.0));
        assert!(close(n("ball_cos"), 0.2 / d) && close(n("ball_sin"), -0.05 / d));
        // 1 cm is visible: 0.04 units.
        assert!(close(n("ball_ahead"), 0.8) && close(n("ball_side"), -0.2));
        assert_eq!(n("ball_in_reach"), 1.0);
        // The opponent goal (3, 0) is 2 m behind and 1 m to the right of it.
        let g = 5.0f32.sqrt();
        assert!(close(n("goal_dist"), g / 6.0));
        assert!(close(n("goal_cos"), -2.0 / g) && close(n("goal_sin"), -1.0 / g));
        let og = 17.0f32.sqrt();
        assert!(close(n("own_goal_cos"), 4.0 / og) && close(n("own_goal_sin"), -1.0 / og));
        // The teammates are players 0, 1 and 3, in that order.
        assert!(close(n("mate1_x"), -0.9) && close(n("mate2_y"), 0.5));
        assert!(close(n("mate2_sin"), 1.0) && close(n("mate3_x"), 0.0));
        assert!(close(n("opp3_sin"), -1.0) && close(n("opp0_y"), 1.0));
        assert!(close(n("ball_vx"), 0.5));
        assert!(close(n("time_left"), 100.0 / 600.0));
        assert_eq!(n("second_half"), 1.0);
        assert!(close(n("score_diff"), (-1.0f32).tanh()));
        assert_eq!(
            [n("sp_kick_off"), n("sp_goal_kick"), n("sp_own")],
            [0.0, 1.0, 1.0]
        );
        assert!(close(n("sp_ticks_left"), 0.5));
        assert_eq!([n("me0"), n("me2")], [0.0, 1.0]);
        // Turned away by 90 degrees, the ball is out of reach.
        obs.own[2].heading = std::f32::consts::FRAC_PI_2;
        scale.encode(&obs, &mut v);
        assert_eq!(named2(&v, "ball_in_reach"), 0.0);
        assert!(!scale.kick.in_reach(&obs));
    }

    #[test]
    fn version_2_rows_zero_the_tail_and_version_3_extends_them() {
        let obs = sample_observation();
        let mut v2 = [7.0; OBS_DIM];
        test_scale(2).encode(&obs, &mut v2);
        assert!(v2[OBS_DIM_V2..].iter().all(|&x| x == 0.0));
        assert_eq!(test_scale(2).dim(), OBS_DIM_V2);
        let mut v3 = [7.0; OBS_DIM];
        test_scale(3).encode(&obs, &mut v3);
        assert_eq!(
            v3[..OBS_DIM_V2],
            v2[..OBS_DIM_V2],
            "version 3 starts with version 2"
        );
        assert_eq!(test_scale(3).dim(), OBS_DIM_V3);
        assert!(v3[OBS_DIM_V3..].iter().all(|&x| x == 0.0));
        let mut v4 = [7.0; OBS_DIM];
        test_scale(4).encode(&obs, &mut v4);
        assert_eq!(
            v4[..OBS_DIM_V3],
            v3[..OBS_DIM_V3],
            "version 4 starts with version 3"
        );
        assert_eq!(test_scale(4).dim(), OBS_DIM);
    }

    #[test]
    fn version_4_encoding_puts_each_quantity_where_documented() {
        let mut obs = sample_observation();
        // Player 2 at (1, -1) faces +x; the ball at (0, -1) is behind it,
        // but the lane is the ball's: from (0, -1) along +x, as long as the
        // ball's distance to the goal (3, 0), sqrt(10) m.
        obs.own[2].heading = 0.0;
        obs.opponents[3].fallen = true;
        let scale = test_scale(4);
        let mut v = [0.0; OBS_DIM];
        scale.encode(&obs, &mut v);
        let close = |a: f32, b: f32| (a - b).abs() < 1e-5;
        let n = |v: &[f32], name: &str| named2(v, name);
        // Standing opponents: 1 and 2 at (0, 0), 1 m from the lane's start;
        // 0 at (3, 2.25). The fallen one at (-0.3, -0.45) does not count.
        assert!(close(n(&v, "shot_lane"), 1.0), "{}", n(&v, "shot_lane"));
        // The segment (0, -1) to (3, 0): the centre is 0.9487 m from it.
        let to_goal = 0.3f32.hypot(0.9);
        assert!(close(n(&v, "goal_lane"), to_goal), "{}", n(&v, "goal_lane"));
        // Along +x from y = -1 the kick meets the goal line 1 m right of the
        // centre: inside the 1.3 m half width.
        assert!(close(n(&v, "shot_aim"), -1.0 / 1.3));
        // Turned onto the goal's centre, the shot's lane is the goal's.
        obs.own[2].heading = 1.0f32.atan2(3.0);
        scale.encode(&obs, &mut v);
        assert!(n(&v, "shot_aim").abs() < 1e-5);
        assert!(close(n(&v, "shot_lane"), n(&v, "goal_lane")));
        // A standing opponent on the line: the lane is shut.
        obs.opponents[3] = RobotObs {
            x: 1.5,
            y: -0.5,
            heading: 0.0,
            fallen: false,
            busy: false,
        };
        scale.encode(&obs, &mut v);
        assert!(n(&v, "shot_lane") < 1e-5 && n(&v, "goal_lane") < 1e-5);
        // Facing away from the goal line, the aim is at its clamp, on the
        // side the heading turns to.
        obs.own[2].heading = 2.0;
        scale.encode(&obs, &mut v);
        assert_eq!(n(&v, "shot_aim"), AIM_CLAMP);
        obs.own[2].heading = -2.0;
        scale.encode(&obs, &mut v);
        assert_eq!(n(&v, "shot_aim"), -AIM_CLAMP);
    }

    #[test]
    fn version_3_encoding_puts_each_quantity_where_documented() {
        let obs = sample_observation();
        let mut v = [0.0; OBS_DIM];
        test_scale(3).encode(&obs, &mut v);
        let n = |name: &str| named2(&v, name);
        let close = |a: f32, b: f32| (a - b).abs() < 1e-5;
        // Player 2 stands at (1, -1) facing -x. Teammate 0 at (-2.7, 0) is
        // 3.7 m ahead of it and 1 m to its right.
        assert!(close(n("mate1_ahead"), 3.7 / 3.0) && close(n("mate1_side"), -1.0 / 3.0));
        // Teammate 1 at (-1.5, 1.125) faces +y; the ball at (0, -1) is
        // below and to its right: cos = (dy) / d with d = |(1.5, -2.125)|.
        let d = 1.5f32.hypot(2.125);
        assert!(close(n("mate2_faces_ball"), -2.125 / d));
        // Teammate 3 at the centre faces +x; the ball (0, -1) lies at 90 degrees.
        assert!(close(n("mate3_faces_ball"), 0.0));
        // Opponents 1 and 2 stand at the centre, on teammate 3 itself: its
        // lane from the ball is blocked at its end.
        assert!(close(n("mate3_lane"), 0.0));
        // Teammate 0's lane from (0, -1) to (-2.7, 0): opponent 3 at
        // (-0.3, -0.45) is the nearest to it.
        let (ux, uy) = (-2.7f32, 1.0f32);
        let (px, py) = (-0.3f32, 0.55f32);
        let t = (ux * px + uy * py) / (ux * ux + uy * uy);
        let lane = (px - t * ux).hypot(py - t * uy);
        assert!(
            close(n("mate1_lane"), lane),
            "{} vs {lane}",
            n("mate1_lane")
        );
        // The nearest opponent to (1, -1) is opponent 3 at (-0.3, -0.45)
        // (the two at the centre are 1.414 m away): 1.3 m ahead and 0.55 m
        // to the right (facing -x, its left is -y).
        assert!(close(n("opp_near_ahead"), 1.3 / 3.0));
        assert!(
            close(n("opp_near_side"), -0.55 / 3.0),
            "{}",
            n("opp_near_side")
        );
    }
}
