//! The global state of a match as one vector: what PettingZoo's `state()`
//! returns (centralised critics, value decomposition). Unlike the
//! observations it belongs to no robot and no team: positions are in the
//! world frame (blue's: blue attacks +x), robots in a fixed order (blue's
//! players 0..3, then red's).
//!
//! Built from the two teams' observations alone (blue's player 0 sees every
//! position in the world frame; red's player 0 says which red robot
//! controls the ball), scaled as observation layout 2 scales them.

use naosoccer_policy::obs::{BALL_SPEED_SCALE, SET_PLAY_TICKS_SCALE};
use naosoccer_policy::ObsScale;
use naosoccer_proto::{Observation, RobotObs, PLAYERS_PER_TEAM};

/// Goals are multiplied by this (the socket env's layout does the same).
pub const SCORE_SCALE: f32 = 0.1;

/// What each robot contributes, in order.
const ROBOT_FIELDS: [&str; 7] = ["x", "y", "cos", "sin", "fallen", "busy", "control"];

/// Length of the state vector.
pub const STATE_DIM: usize = 4 + 2 * PLAYERS_PER_TEAM * ROBOT_FIELDS.len() + 4 + 6;

/// The entries' names, in order (docs/PYTHON.md lists them).
pub fn state_names() -> Vec<String> {
    let mut names: Vec<String> = ["ball_x", "ball_y", "ball_vx", "ball_vy"]
        .map(String::from)
        .to_vec();
    for team in ["blue", "red"] {
        for p in 0..PLAYERS_PER_TEAM {
            names.extend(ROBOT_FIELDS.iter().map(|f| format!("{team}{p}_{f}")));
        }
    }
    names.extend(
        [
            "time_left",
            "second_half",
            "score_blue",
            "score_red",
            "sp_kick_off",
            "sp_kick_in",
            "sp_goal_kick",
            "sp_corner_kick",
            "sp_blue",
            "sp_ticks_left",
        ]
        .map(String::from),
    );
    names
}

/// Writes the state seen in `blue` (an observation of a blue robot) and
/// `red` (one of a red robot, of the same tick) into `out` ([`STATE_DIM`]).
pub fn write_state(scale: &ObsScale, blue: &Observation, red: &Observation, out: &mut [f32]) {
    assert_eq!(out.len(), STATE_DIM, "the state has STATE_DIM entries");
    let (sx, sy) = (1.0 / scale.half_length, 1.0 / scale.half_width);
    let flag = |b: bool| f32::from(u8::from(b));
    out[0] = blue.ball.x * sx;
    out[1] = blue.ball.y * sy;
    out[2] = blue.ball.vx / BALL_SPEED_SCALE;
    out[3] = blue.ball.vy / BALL_SPEED_SCALE;
    let mut i = 4;
    let mut robot = |r: &RobotObs, control: bool| {
        let row = [
            r.x * sx,
            r.y * sy,
            r.heading.cos(),
            r.heading.sin(),
            flag(r.fallen),
            flag(r.busy),
            flag(control),
        ];
        out[i..i + row.len()].copy_from_slice(&row);
        i += row.len();
    };
    for p in 0..PLAYERS_PER_TEAM {
        robot(&blue.own[p], blue.control[p]);
    }
    // Red's robots from blue's view: the world frame.
    for p in 0..PLAYERS_PER_TEAM {
        robot(&blue.opponents[p], red.control[p]);
    }
    let tail = &mut out[4 + 2 * PLAYERS_PER_TEAM * ROBOT_FIELDS.len()..];
    tail[0] = (blue.time_left / scale.match_seconds).clamp(0.0, 1.0);
    tail[1] = flag(blue.half >= 2);
    tail[2] = blue.score.own as f32 * SCORE_SCALE;
    tail[3] = blue.score.opponent as f32 * SCORE_SCALE;
    tail[4..].fill(0.0);
    if let Some(sp) = &blue.set_play {
        tail[4 + sp.kind.index()] = 1.0;
        tail[8] = flag(sp.own);
        tail[9] = (sp.ticks_left as f32 / SET_PLAY_TICKS_SCALE).min(1.0);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use naosoccer_proto::Team;
    use naosoccer_referee::{blank_observation, Match, MatchConfig};

    #[test]
    fn the_state_is_the_world_seen_by_both_teams() {
        let names = state_names();
        assert_eq!(names.len(), STATE_DIM);
        let at = |n: &str| names.iter().position(|m| m == n).unwrap();
        let cfg = MatchConfig::default();
        let mut m = Match::new(&cfg, 5).unwrap();
        let (mut blue, mut red) = (blank_observation(), blank_observation());
        let scale = ObsScale::from_config(&cfg);
        let mut s = vec![0.0; STATE_DIM];
        // A few ticks in, so that robots have moved and the clock runs.
        for _ in 0..30 {
            m.step(&[naosoccer_proto::Action::Forward; naosoccer_proto::ROBOTS]);
        }
        m.observe_into(Team::Blue, 1, &mut blue);
        m.observe_into(Team::Red, 2, &mut red);
        write_state(&scale, &blue, &red, &mut s);
        assert!((s[at("ball_x")] - blue.ball.x / scale.half_length).abs() < 1e-6);
        // Red sees itself mirrored: its own x is minus the world's.
        for p in 0..PLAYERS_PER_TEAM {
            let x = s[at(&format!("red{p}_x"))] * scale.half_length;
            assert!((x + red.own[p].x).abs() < 1e-5, "red {p}");
            let c = s[at(&format!("blue{p}_cos"))];
            assert!((c - blue.own[p].heading.cos()).abs() < 1e-6, "blue {p}");
        }
        let t = s[at("time_left")];
        assert!(t > 0.0 && t < 1.0, "{t}");
        // The same state whichever robots observed it (to the last bit or
        // so: an observation's positions are computed around its robot).
        let mut other = vec![0.0; STATE_DIM];
        m.observe_into(Team::Blue, 3, &mut blue);
        m.observe_into(Team::Red, 0, &mut red);
        write_state(&scale, &blue, &red, &mut other);
        for (k, (a, b)) in s.iter().zip(&other).enumerate() {
            assert!((a - b).abs() < 1e-6, "{}: {a} vs {b}", names[k]);
        }
    }
}
