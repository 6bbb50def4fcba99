//! The paper's rule-based team (section II.A), over the observation only.
//!
//! Every field player computes the same role assignment from the same
//! observation: the teammate closest to the ball (or the one controlling it)
//! engages, the other two take support places. Engaging follows the paper:
//! face the ball (turn while the heading deviation `dtheta` exceeds `b_rad`),
//! approach with `forward`, take control, and `shoot` when the distance
//! condition (ball near the opponent goal, within the goal's width) and the
//! angle condition (robot, ball and goal centre nearly on one line,
//! `|dtheta_target| < b_shoot`) both hold; otherwise dribble on, or first walk
//! round behind the ball so that the line to goal opens. With the ball at its
//! feet a player also passes to a teammate ahead in its line of fire and
//! clears from its own half. Player 0 keeps goal: it stays on its line
//! following the ball, and only engages when the ball enters its zone.
//!
//! The only memory is per robot (turning hysteresis), so one instance per
//! robot, as the server and runner build them, is deterministic.

use naosoccer_proto::msg::Pitch;
use naosoccer_proto::{Action, Observation, RobotObs, PLAYERS_PER_TEAM};
use serde::{Deserialize, Serialize};

use super::Policy;

/// The scripted team's parameters. The defaults' pitch sizes and `b_rad`
/// are those of `assets/match.toml` (a test in crates/referee keeps them
/// equal); a server's scripted fill takes them from its match's
/// configuration ([`ScriptedParams::for_pitch`]). The kick reach is tuned a
/// margin inside the sim's `kick_reach_min`/`kick_reach_max` and the
/// protocol does not announce it, so it stays a parameter: deriving it from
/// the configuration would change how the team plays, and with it every
/// recorded match and shipped evaluation against it.
///
/// A variant names the fields it changes, as `KEY=VAL,...` after `scripted:`
/// or as a TOML file of `KEY = VAL` lines ([`ScriptedParams::parse_spec`]);
/// the others keep their defaults.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ScriptedParams {
    /// Half the field length (m): goals at x = +/- this.
    pub half_length: f32,
    /// Half the goal mouth (m).
    pub goal_half_width: f32,
    /// Facing the ball: `|dtheta| < b_rad` (rad).
    pub b_rad: f32,
    /// The angle condition for a shot, `|dtheta_target| < b_shoot` (rad).
    pub b_shoot: f32,
    /// The distance condition: the ball at most this far from the opponent goal line (m).
    pub shoot_range: f32,
    /// Where the kick reaches, ahead of the torso (m)...
    pub reach_min: f32,
    pub reach_max: f32,
    /// ...and sideways.
    pub reach_half_width: f32,
    /// Within this angle (rad) of the ball-to-goal line the player attacks the
    /// ball directly; outside it walks round behind the ball first.
    pub align_tolerance: f32,
    /// How far behind the ball the player lines up (m).
    pub behind: f32,
    /// Passes go to teammates at most this far (m)...
    pub pass_range: f32,
    /// ...within this angle of the heading (rad).
    pub pass_cone: f32,
    /// The keeper engages when the ball is this close to its goal line (m).
    pub keeper_zone: f32,
    /// With an opponent this close to the ball (m), a player kicks instead of dribbling.
    pub contest_radius: f32,
    /// Start turning above this angle error, stop below the smaller one (rad).
    pub turn_start: f32,
    pub turn_stop: f32,
    /// A support player counts as in place within this distance (m).
    pub arrive: f32,
    /// The first support player waits this far ahead of the ball (m)...
    pub support_ahead: f32,
    /// ...the second covers this far behind it (m)...
    pub cover_behind: f32,
    /// ...but no further forward than this x (m): how high the team presses.
    pub cover_max_x: f32,
}

impl Default for ScriptedParams {
    fn default() -> Self {
        ScriptedParams {
            half_length: 3.0,
            goal_half_width: 1.3,
            b_rad: 0.4,
            b_shoot: 0.25,
            shoot_range: 2.0,
            reach_min: 0.105,
            reach_max: 0.25,
            reach_half_width: 0.08,
            align_tolerance: 0.5,
            behind: 0.3,
            pass_range: 2.5,
            pass_cone: 0.35,
            keeper_zone: 1.6,
            contest_radius: 0.5,
            turn_start: 0.35,
            turn_stop: 0.12,
            arrive: 0.3,
            support_ahead: 1.3,
            cover_behind: 1.2,
            cover_max_x: 1.0,
        }
    }
}

impl ScriptedParams {
    /// The defaults on `pitch` (as `joined` announces it, or
    /// `Match::pitch`): half the field length, half the goal width and
    /// `b_rad` from it. On the default pitch: the defaults.
    pub fn for_pitch(pitch: &Pitch) -> ScriptedParams {
        ScriptedParams {
            half_length: pitch.field_length / 2.0,
            goal_half_width: pitch.goal_width / 2.0,
            b_rad: pitch.b_rad,
            ..ScriptedParams::default()
        }
    }

    /// The field names, alphabetically.
    pub fn keys() -> Vec<String> {
        match serde_json::to_value(ScriptedParams::default()) {
            Ok(serde_json::Value::Object(m)) => m.keys().cloned().collect(),
            _ => Vec::new(),
        }
    }

    /// Parses what follows `scripted:` in a policy spec: `KEY=VAL,KEY=VAL`
    /// (the fields of this struct, in metres and radians) or the path of a
    /// TOML file (ending in `.toml`) holding `KEY = VAL` lines. Fields not
    /// named keep their defaults; unknown keys, numbers that do not parse
    /// and values that make no sense (see [`ScriptedParams::validate`]) are
    /// errors that say which.
    pub fn parse_spec(spec: &str) -> Result<ScriptedParams, String> {
        let p = if spec.ends_with(".toml") {
            let text = std::fs::read_to_string(spec).map_err(|e| format!("reading {spec}: {e}"))?;
            toml::from_str::<ScriptedParams>(&text).map_err(|e| format!("{spec}: {e}"))?
        } else {
            let mut map = match serde_json::to_value(ScriptedParams::default()) {
                Ok(serde_json::Value::Object(m)) => m,
                _ => return Err("scripted parameters do not serialise".into()),
            };
            for item in spec.split(',') {
                let (key, val) = item
                    .split_once('=')
                    .ok_or_else(|| format!("expected KEY=VAL, got {item:?}"))?;
                let key = key.trim();
                if !map.contains_key(key) {
                    return Err(format!(
                        "unknown scripted parameter {key:?} (known: {})",
                        ScriptedParams::keys().join(", ")
                    ));
                }
                let v: f32 = val
                    .trim()
                    .parse()
                    .map_err(|_| format!("{key}: {val:?} is not a number"))?;
                if !v.is_finite() {
                    return Err(format!("{key} must be a finite number, got {v}"));
                }
                map.insert(key.to_string(), serde_json::json!(v));
            }
            serde_json::from_value(serde_json::Value::Object(map)).map_err(|e| e.to_string())?
        };
        p.validate()?;
        Ok(p)
    }

    /// Every value finite; lengths, angles and ranges positive; the kick
    /// reach a non-empty interval; the turning hysteresis ordered.
    pub fn validate(&self) -> Result<(), String> {
        let positive = [
            ("half_length", self.half_length),
            ("goal_half_width", self.goal_half_width),
            ("b_rad", self.b_rad),
            ("b_shoot", self.b_shoot),
            ("shoot_range", self.shoot_range),
            ("reach_max", self.reach_max),
            ("reach_half_width", self.reach_half_width),
            ("pass_range", self.pass_range),
            ("pass_cone", self.pass_cone),
            ("turn_start", self.turn_start),
            ("arrive", self.arrive),
        ];
        let non_negative = [
            ("reach_min", self.reach_min),
            ("align_tolerance", self.align_tolerance),
            ("behind", self.behind),
            ("keeper_zone", self.keeper_zone),
            ("contest_radius", self.contest_radius),
            ("turn_stop", self.turn_stop),
            ("support_ahead", self.support_ahead),
            ("cover_behind", self.cover_behind),
        ];
        for (k, v) in positive {
            if !(v.is_finite() && v > 0.0) {
                return Err(format!("{k} must be a positive number, got {v}"));
            }
        }
        for (k, v) in non_negative {
            if !(v.is_finite() && v >= 0.0) {
                return Err(format!("{k} must be a number >= 0, got {v}"));
            }
        }
        if !self.cover_max_x.is_finite() {
            return Err(format!(
                "cover_max_x must be a finite number, got {}",
                self.cover_max_x
            ));
        }
        if self.reach_min >= self.reach_max {
            return Err(format!(
                "reach_min ({}) must be below reach_max ({})",
                self.reach_min, self.reach_max
            ));
        }
        if self.turn_stop > self.turn_start {
            return Err(format!(
                "turn_stop ({}) must not exceed turn_start ({})",
                self.turn_stop, self.turn_start
            ));
        }
        Ok(())
    }

    /// The fields that differ from the defaults as `KEY=VAL,...`,
    /// alphabetically (empty for the defaults); parses back to `self`.
    pub fn diff_spec(&self) -> String {
        let (Ok(serde_json::Value::Object(mine)), Ok(serde_json::Value::Object(base))) = (
            serde_json::to_value(self),
            serde_json::to_value(ScriptedParams::default()),
        ) else {
            return String::new();
        };
        let mut parts = Vec::new();
        for (k, v) in &mine {
            if base.get(k) != Some(v) {
                // f32 values went to JSON as f64; print the f32 so the text
                // is the shortest that parses back to the same bits.
                let x = v.as_f64().unwrap_or(f64::NAN) as f32;
                parts.push(format!("{k}={x}"));
            }
        }
        parts.join(",")
    }
}

/// One robot's scripted player.
#[derive(Debug, Clone)]
pub struct Scripted {
    p: ScriptedParams,
    /// Turning towards a target until the error is small (hysteresis).
    turning: bool,
    /// Heading when the last turn was asked for: a robot wedged between
    /// others turns without its heading changing.
    turned_from: Option<f32>,
    /// Ticks in a row a turn did not move the heading.
    stuck: u32,
    /// Ticks left walking out of a jam.
    escape: u32,
}

/// Ticks of turning without effect before a player walks out of a jam.
const STUCK_TICKS: u32 = 20;
/// Ticks it then walks.
const ESCAPE_TICKS: u32 = 8;

impl Scripted {
    pub fn new(p: ScriptedParams) -> Scripted {
        Scripted {
            p,
            turning: false,
            turned_from: None,
            stuck: 0,
            escape: 0,
        }
    }

    fn decide(&mut self, obs: &Observation) -> Action {
        if obs.player.index() == 0 {
            self.keeper(obs)
        } else {
            self.field_player(obs)
        }
    }

    fn keeper(&mut self, obs: &Observation) -> Action {
        let p = &self.p;
        let me = obs.me();
        let ball = [obs.ball.x, obs.ball.y];
        let own_line = -p.half_length;
        if ball[0] < own_line + p.keeper_zone && ball[1].abs() < p.goal_half_width + 0.6 {
            return self.engage(obs, true);
        }
        let home = [own_line + 0.35, (ball[1] * 0.4).clamp(-0.7, 0.7)];
        if dist([me.x, me.y], home) > p.arrive {
            self.go_to(me, home)
        } else {
            self.face(me, ball)
        }
    }

    fn field_player(&mut self, obs: &Observation) -> Action {
        let me_idx = obs.player.index();
        let ball = [obs.ball.x, obs.ball.y];
        let engager = engager(obs);
        if engager == Some(me_idx) {
            return self.engage(obs, false);
        }
        // Support places, by rank among the non-engaging field players.
        let rank = (1..PLAYERS_PER_TEAM)
            .filter(|&i| Some(i) != engager && i < me_idx)
            .count();
        let side = if ball[1] >= 0.0 { -1.0 } else { 1.0 };
        let hl = self.p.half_length;
        let spot = if rank == 0 {
            // Ahead of the ball, across from it: a pass or a rebound comes here.
            [
                (ball[0] + self.p.support_ahead).clamp(-1.5, hl - 0.7),
                (ball[1] + side * 0.7).clamp(-1.6, 1.6),
            ]
        } else {
            // Behind the ball, covering the middle.
            [
                (ball[0] - self.p.cover_behind).clamp(-hl + 1.0, self.p.cover_max_x.max(-hl + 1.0)),
                (ball[1] * 0.5).clamp(-1.2, 1.2),
            ]
        };
        let me = obs.me();
        if dist([me.x, me.y], spot) > self.p.arrive {
            self.go_to(me, spot)
        } else {
            self.face(me, ball)
        }
    }

    /// Go for the ball and play it towards the opponent goal.
    fn engage(&mut self, obs: &Observation, keeper: bool) -> Action {
        let p = self.p;
        let me = obs.me();
        let pos = [me.x, me.y];
        let ball = [obs.ball.x, obs.ball.y];
        let goal = [p.half_length, 0.0];
        let to_goal = sub(goal, ball);
        let line = to_goal[1].atan2(to_goal[0]);
        let to_ball = sub(ball, pos);
        let d = norm(to_ball);
        let ball_dir = to_ball[1].atan2(to_ball[0]);
        // The paper's dtheta (heading to ball) and dtheta_target (robot, ball, goal alignment).
        let dtheta = wrap(ball_dir - me.heading);
        let dtheta_target = wrap(ball_dir - line);

        if dtheta_target.abs() < p.align_tolerance
            || (d < 0.25 && dtheta_target.abs() < 2.0 * p.align_tolerance)
        {
            let (fwd, lat) = local(me, ball);
            let in_reach =
                fwd >= p.reach_min && fwd <= p.reach_max && lat.abs() <= p.reach_half_width;
            if in_reach {
                let distance_ok =
                    ball[0] > p.half_length - p.shoot_range && ball[1].abs() < p.goal_half_width;
                if distance_ok && dtheta_target.abs() < p.b_shoot {
                    return Action::Shoot;
                }
                if self.pass_open(obs) {
                    return Action::Shoot;
                }
                // Challenged: kick it on rather than push against the opponent.
                let contested = obs
                    .opponents
                    .iter()
                    .any(|o| !o.fallen && dist([o.x, o.y], ball) < p.contest_radius);
                if contested && wrap(me.heading).abs() < std::f32::consts::FRAC_PI_2 {
                    return Action::Shoot;
                }
                // Clear the ball out of the own half, roughly forwards.
                let clear_cone = if keeper { 0.9 } else { 0.5 };
                if ball[0] < -0.5 && wrap(me.heading).abs() < clear_cone {
                    return Action::Shoot;
                }
            }
            if dtheta.abs() > p.b_rad || (self.turning && dtheta.abs() > p.turn_stop) {
                self.turning = true;
                return turn_towards(dtheta);
            }
            self.turning = false;
            return Action::Forward;
        }

        // Walk round behind the ball; go wide when the ball is in the way.
        let u = scale(to_goal, 1.0 / norm(to_goal).max(1e-6));
        let rel = sub(pos, ball);
        let along = dot(rel, u);
        let across = cross(u, rel);
        let target = if along > -0.15 && across.abs() < 0.45 {
            let side = if across >= 0.0 { 1.0 } else { -1.0 };
            let perp = [-u[1] * side, u[0] * side];
            add(ball, add(scale(perp, 0.5), scale(u, -0.15)))
        } else {
            sub(ball, scale(u, p.behind))
        };
        self.go_to(me, target)
    }

    /// A teammate ahead in the line of fire, with no opponent near the lane.
    fn pass_open(&self, obs: &Observation) -> bool {
        let p = &self.p;
        let me = obs.me();
        let ball = [obs.ball.x, obs.ball.y];
        obs.own.iter().enumerate().any(|(i, t)| {
            if i == obs.player.index() || t.fallen || t.x < ball[0] + 0.3 {
                return false;
            }
            let lane = sub([t.x, t.y], ball);
            let len = norm(lane);
            if !(0.8..=p.pass_range).contains(&len) {
                return false;
            }
            if wrap(lane[1].atan2(lane[0]) - me.heading).abs() > p.pass_cone {
                return false;
            }
            let u = scale(lane, 1.0 / len);
            !obs.opponents.iter().any(|o| {
                let rel = sub([o.x, o.y], ball);
                let along = dot(rel, u);
                along > 0.0 && along < len && cross(u, rel).abs() < 0.4
            })
        })
    }

    fn go_to(&mut self, me: &RobotObs, target: [f32; 2]) -> Action {
        let to = sub(target, [me.x, me.y]);
        let err = wrap(to[1].atan2(to[0]) - me.heading);
        if self.steer(err) {
            turn_towards(err)
        } else {
            Action::Forward
        }
    }

    fn face(&mut self, me: &RobotObs, target: [f32; 2]) -> Action {
        let to = sub(target, [me.x, me.y]);
        let err = wrap(to[1].atan2(to[0]) - me.heading);
        if self.steer(err) {
            turn_towards(err)
        } else {
            Action::Stay
        }
    }

    /// Whether to turn now: start above `turn_start`, keep on until below `turn_stop`.
    fn steer(&mut self, err: f32) -> bool {
        let e = err.abs();
        self.turning = if self.turning {
            e > self.p.turn_stop
        } else {
            e > self.p.turn_start
        };
        self.turning
    }
}

impl Policy for Scripted {
    fn act(&mut self, obs: &Observation) -> Action {
        let heading = obs.me().heading;
        if obs.me().fallen {
            self.turning = false;
            self.turned_from = None;
            self.stuck = 0;
            self.escape = 0;
            return Action::Stay;
        }
        if let Some(from) = self.turned_from.take() {
            if wrap(heading - from).abs() < 0.01 {
                self.stuck += 1;
            } else {
                self.stuck = 0;
            }
        } else {
            self.stuck = 0;
        }
        if self.stuck >= STUCK_TICKS {
            self.stuck = 0;
            self.escape = ESCAPE_TICKS;
            self.turning = false;
        }
        if self.escape > 0 {
            self.escape -= 1;
            return Action::Forward;
        }
        let action = self.decide(obs);
        if matches!(action, Action::TurnLeft | Action::TurnRight) {
            self.turned_from = Some(heading);
        }
        action
    }

    fn name(&self) -> &str {
        "scripted"
    }
}

/// The field player (1..=3) that goes for the ball: the one in control, else
/// the closest standing one (lower number on a tie).
fn engager(obs: &Observation) -> Option<usize> {
    if let Some(i) = (1..PLAYERS_PER_TEAM).find(|&i| obs.control[i]) {
        return Some(i);
    }
    let ball = [obs.ball.x, obs.ball.y];
    (1..PLAYERS_PER_TEAM)
        .filter(|&i| !obs.own[i].fallen)
        .map(|i| (dist([obs.own[i].x, obs.own[i].y], ball), i))
        .fold(None, |best: Option<(f32, usize)>, c| match best {
            Some(b) if b.0 <= c.0 => Some(b),
            _ => Some(c),
        })
        .map(|(_, i)| i)
}

fn turn_towards(err: f32) -> Action {
    if err > 0.0 {
        Action::TurnLeft
    } else {
        Action::TurnRight
    }
}

/// The ball in the robot's frame: (ahead, to the left).
fn local(me: &RobotObs, p: [f32; 2]) -> (f32, f32) {
    let d = sub(p, [me.x, me.y]);
    let (s, c) = me.heading.sin_cos();
    (d[0] * c + d[1] * s, -d[0] * s + d[1] * c)
}

fn wrap(a: f32) -> f32 {
    use std::f32::consts::{PI, TAU};
    let a = a % TAU;
    if a > PI {
        a - TAU
    } else if a <= -PI {
        a + TAU
    } else {
        a
    }
}

fn sub(a: [f32; 2], b: [f32; 2]) -> [f32; 2] {
    [a[0] - b[0], a[1] - b[1]]
}
fn add(a: [f32; 2], b: [f32; 2]) -> [f32; 2] {
    [a[0] + b[0], a[1] + b[1]]
}
fn scale(a: [f32; 2], k: f32) -> [f32; 2] {
    [a[0] * k, a[1] * k]
}
fn dot(a: [f32; 2], b: [f32; 2]) -> f32 {
    a[0] * b[0] + a[1] * b[1]
}
fn cross(a: [f32; 2], b: [f32; 2]) -> f32 {
    a[0] * b[1] - a[1] * b[0]
}
fn norm(a: [f32; 2]) -> f32 {
    a[0].hypot(a[1])
}
fn dist(a: [f32; 2], b: [f32; 2]) -> f32 {
    norm(sub(a, b))
}

#[cfg(test)]
mod tests {
    use super::*;
    use naosoccer_proto::Tick;
    use naosoccer_proto::{BallObs, Team};

    fn obs(player: u8, me: RobotObs, ball: [f32; 2]) -> Observation {
        let mut own = [RobotObs {
            x: -2.0,
            y: 2.0,
            heading: 0.0,
            fallen: false,
            busy: false,
        }; PLAYERS_PER_TEAM];
        // Teammates far away so `me` is the engager.
        for (i, r) in own.iter_mut().enumerate() {
            r.y = 2.0 - i as f32 * 0.1;
            r.x = -2.9;
        }
        own[player as usize] = me;
        Observation {
            tick: Tick::ZERO,
            team: Team::Blue,
            player: naosoccer_proto::Player::new(player as usize).unwrap(),
            time_left: 600.0,
            score: Default::default(),
            own,
            opponents: [RobotObs {
                x: 2.5,
                y: -2.0,
                heading: std::f32::consts::PI,
                fallen: false,
                busy: false,
            }; PLAYERS_PER_TEAM],
            ball: BallObs {
                x: ball[0],
                y: ball[1],
                vx: 0.0,
                vy: 0.0,
            },
            control: [false; PLAYERS_PER_TEAM],
            opponent_control: false,
            reward: 0.0,
            half: 1,
            set_play: None,
        }
    }

    fn robot(x: f32, y: f32, heading: f32) -> RobotObs {
        RobotObs {
            x,
            y,
            heading,
            fallen: false,
            busy: false,
        }
    }

    #[test]
    fn turns_to_face_the_ball_then_approaches() {
        let mut s = Scripted::new(ScriptedParams::default());
        // Ball straight ahead towards the goal but the robot looks left.
        let o = obs(1, robot(0.0, 0.0, 1.2), [1.0, 0.0]);
        assert_eq!(s.act(&o), Action::TurnRight);
        let o = obs(1, robot(0.0, 0.0, 0.0), [1.0, 0.0]);
        let mut s = Scripted::new(ScriptedParams::default());
        assert_eq!(s.act(&o), Action::Forward);
    }

    #[test]
    fn shoots_only_when_distance_and_angle_conditions_hold() {
        let mut s = Scripted::new(ScriptedParams::default());
        // In reach, aligned with the goal, close to it.
        let o = obs(1, robot(2.0, 0.0, 0.0), [2.18, 0.0]);
        assert_eq!(s.act(&o), Action::Shoot);
        // Same alignment far from goal in the opponent half: dribble on.
        let o = obs(1, robot(-0.2, 0.0, 0.0), [-0.02, 0.0]);
        assert_eq!(s.act(&o), Action::Forward);
        // Close to goal but robot-ball-goal not aligned: no shot.
        let o = obs(1, robot(2.0, -1.0, 0.0), [2.18, -1.0]);
        assert_ne!(s.act(&o), Action::Shoot);
    }

    #[test]
    fn a_variant_with_a_longer_range_shoots_where_the_default_dribbles() {
        let o = obs(1, robot(-0.2, 0.0, 0.0), [-0.02, 0.0]);
        let mut s = Scripted::new(ScriptedParams::default());
        assert_eq!(s.act(&o), Action::Forward);
        let far = ScriptedParams::parse_spec("shoot_range=3.5").unwrap();
        assert_eq!(Scripted::new(far).act(&o), Action::Shoot);
    }

    #[test]
    fn the_shipped_variants_parse_and_differ_from_the_default() {
        let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/../../assets/scripted");
        let mut names: Vec<_> = std::fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().path())
            .collect();
        names.sort();
        assert!(names.len() >= 2, "{names:?}");
        for path in names {
            let p = ScriptedParams::parse_spec(path.to_str().unwrap()).unwrap();
            assert_ne!(p, ScriptedParams::default(), "{}", path.display());
        }
    }

    #[test]
    fn keeper_stays_home_until_the_ball_comes_near() {
        let mut s = Scripted::new(ScriptedParams::default());
        // At home, ball far away in front: just faces it.
        let o = obs(0, robot(-2.65, 0.0, 0.0), [1.0, 0.0]);
        assert_eq!(s.act(&o), Action::Stay);
        // Ball in its zone, straight ahead: goes for it.
        let o = obs(0, robot(-2.65, 0.0, 0.0), [-2.0, 0.0]);
        assert_eq!(s.act(&o), Action::Forward);
    }

    #[test]
    fn fallen_robot_stays() {
        let mut s = Scripted::new(ScriptedParams::default());
        let mut me = robot(0.0, 0.0, 0.0);
        me.fallen = true;
        assert_eq!(s.act(&obs(2, me, [0.5, 0.0])), Action::Stay);
    }
}
