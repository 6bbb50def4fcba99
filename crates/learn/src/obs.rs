//! The observation vector: `proto::Observation` flattened into the fixed f32
//! layout the networks read. Versioned: a checkpoint records the version it
//! was trained on and refuses to load under another. docs/LEARNING.md lists
//! the same layout; a test checks the two agree.
//!
//! Everything is in the acting team's frame (the referee mirrors red's view,
//! so a team always attacks +x), positions divided by the half-field sizes so
//! the pitch spans [-1, 1] in both axes.

use naosoccer_proto::{Observation, RobotObs, PLAYERS_PER_TEAM};
use serde::{Deserialize, Serialize};

/// Bumped whenever the layout below changes.
pub const OBS_VERSION: u32 = 1;

/// Length of the observation vector.
pub const OBS_DIM: usize = 48;

/// Ball speeds are divided by this (m/s): a hard kick is a few m/s.
pub const BALL_SPEED_SCALE: f32 = 2.0;

/// The name of every entry, in order, as docs/LEARNING.md lists them.
#[rustfmt::skip]
pub const FEATURE_NAMES: [&str; OBS_DIM] = [
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

/// How positions are normalised: the pitch's half sizes in metres. Stored in
/// every checkpoint, so a policy normalises as it was trained.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ObsScale {
    pub half_length: f32,
    pub half_width: f32,
}

impl ObsScale {
    pub fn from_config(cfg: &naosoccer_referee::MatchConfig) -> ObsScale {
        let f = naosoccer_referee::Field::from_sim(&cfg.sim);
        ObsScale {
            half_length: f.half_length,
            half_width: f.half_width,
        }
    }

    /// Writes the observation vector for the robot that received `obs` into
    /// `out` (length [`OBS_DIM`]). Allocation-free: training calls this for
    /// every robot every tick.
    pub fn encode(&self, obs: &Observation, out: &mut [f32]) {
        assert_eq!(
            out.len(),
            OBS_DIM,
            "observation buffer must hold OBS_DIM values"
        );
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
        let me = obs.player as usize % PLAYERS_PER_TEAM;
        for p in 0..PLAYERS_PER_TEAM {
            out[40 + p] = if p == me { 1.0 } else { 0.0 };
        }
        out[44] = f32::from(u8::from(obs.opponent_control));
        // The ball seen from the acting robot (forward, left), which the
        // rotation decisions hinge on; the network could derive it, but only
        // through a product of inputs that small MLPs learn slowly.
        let r = &obs.own[me];
        let (dx, dy) = (obs.ball.x - r.x, obs.ball.y - r.y);
        let (s, c) = r.heading.sin_cos();
        out[45] = (c * dx + s * dy) * sx;
        out[46] = (-s * dx + c * dy) * sx;
        out[47] = f32::from(u8::from(r.fallen));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use naosoccer_proto::{BallObs, ScoreObs, Team};

    /// The observation-layout table of docs/LEARNING.md: rows `| index | name | ... |`
    /// between the two layout markers.
    fn documented_layout() -> Vec<(usize, String)> {
        let doc = include_str!("../../../docs/LEARNING.md");
        let start = doc
            .find("<!-- obs-layout:begin -->")
            .expect("layout start marker in docs/LEARNING.md");
        let end = doc
            .find("<!-- obs-layout:end -->")
            .expect("layout end marker in docs/LEARNING.md");
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
    fn layout_matches_its_documentation() {
        let doc = documented_layout();
        assert_eq!(
            doc.len(),
            OBS_DIM,
            "docs/LEARNING.md lists every entry once"
        );
        for (i, (index, name)) in doc.iter().enumerate() {
            assert_eq!(*index, i, "entries in order");
            assert_eq!(name, FEATURE_NAMES[i], "entry {i}");
        }
        let doc = include_str!("../../../docs/LEARNING.md");
        assert!(
            doc.contains(&format!("version {OBS_VERSION}")),
            "docs name the layout version"
        );
    }

    fn named(v: &[f32], name: &str) -> f32 {
        v[FEATURE_NAMES.iter().position(|n| *n == name).unwrap()]
    }

    #[test]
    fn encoding_puts_each_quantity_where_documented() {
        let scale = ObsScale {
            half_length: 3.0,
            half_width: 2.25,
        };
        let robot = |x: f32, y: f32, heading: f32, fallen: bool| RobotObs {
            x,
            y,
            heading,
            fallen,
            busy: false,
        };
        let obs = Observation {
            tick: 7,
            team: Team::Red,
            player: 2,
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
        };
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
}
