//! The scripted team's parameters: the defaults, the ladder's levels, the
//! `scripted:...` specs that change them, and their checks.

use naosoccer_proto::msg::Pitch;
use serde::{Deserialize, Serialize};

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
    /// Walking round the ball when it is in the way (the player stands
    /// less than 0.15 m behind the ball on its line to the goal and less
    /// than 0.45 m to the side of it), the player first heads for a point
    /// 0.5 m beside the ball and this far behind it (m). 0.15, the
    /// default, puts that point on the edge of the region, where a player
    /// can sway across the edge turning left and right for ever; 0.3 (as
    /// `behind`) puts it outside, as the learned teams' `approach` does.
    pub wide_behind: f32,
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
    /// Reaction: a player decides only every this many control ticks (a
    /// whole number, 1 or more; player `i` on the ticks where
    /// `(tick + i) % react_ticks == 0`) and repeats its last action in
    /// between. 1: every tick (off).
    pub react_ticks: f32,
    /// With `react_ticks` above 1: whether a turn is held like the other
    /// actions (1), or a turning player decides again every tick (0).
    pub hold_turns: f32,
    /// Passing: at 1, a player at the ball passes with `pass` (the
    /// protocol's kick toward the teammate [`naosoccer_proto::pass_receiver`]
    /// names) whenever that teammate stands ahead of the ball, instead of
    /// kicking straight ahead when a teammate is in its line of fire
    /// (`pass_range`, `pass_cone`). 0: off.
    pub aimed_pass: f32,
    /// Aim: a shot aims this far (m) from the goal centre toward the post
    /// farther from the opponents' keeper, and the angle condition is taken
    /// against that point. 0: the centre (off).
    pub aim_offset: f32,
    /// Keeper: when above 0, the keeper's place is on the line from its goal
    /// centre to the ball, this far (m) from the goal centre, instead of on
    /// its line following the ball's y. 0: off.
    pub keeper_guard: f32,
    /// Marking: how many of the two field players that do not engage (0, 1
    /// or 2) mark an opponent instead of taking a support place: the
    /// covering player first. A marker stands `mark_gap` goal-side of the
    /// opponent nearest its own goal (the next one for the second marker),
    /// leaving out the opponent nearest the ball and any opponent more than
    /// `mark_range` from the own goal centre. 0: off.
    pub markers: f32,
    /// See `markers` (m).
    pub mark_gap: f32,
    /// See `markers` (m).
    pub mark_range: f32,
    /// Defending set plays: how many field players (0 to 3, nearest the
    /// ball first) guard at the other team's kick-off or set play instead
    /// of going for the ball: the nearest stands on the line from the ball
    /// to the own goal, `keep_out` from the ball; the second and third in
    /// the lanes from the ball to the two opponents most likely to receive
    /// (nearest the ball after the taker), `keep_out` from the ball or
    /// goal-side of the receiver when it is closer. The others play as
    /// usual (they go for the ball and wait at the edge of the circle).
    /// 0: off.
    pub set_play_guard: f32,
    /// See `set_play_guard`: just outside the referee's keep-out distance
    /// (`set_play_distance`, 0.6 m by default), which the observation does
    /// not carry (m).
    pub keep_out: f32,
    /// Taking set plays: when 1, at the team's own kick-off or set play the
    /// player at the ball plays it with `pass` when a teammate can receive
    /// ([`naosoccer_proto::pass_receiver`]) and, with more than
    /// `set_play_wait` seconds of the set play left, waits for one;
    /// otherwise it plays on as usual. 0: off.
    pub set_play_pass: f32,
    /// See `set_play_pass` (s).
    pub set_play_wait: f32,
    /// Shooting on sight: above 0, a player with the ball in reach also
    /// shoots when the line of its heading from the ball crosses the goal
    /// line between the posts, `shot_margin` inside them, and the ball is at
    /// most this far from the opponent goal centre (m), whatever the
    /// ball-to-goal alignment. 0: off (only the paper's shot conditions).
    pub shot_line: f32,
    /// See `shot_line` (m).
    pub shot_margin: f32,
    /// Clearing: a player at the ball whose heading is within 0.5 rad of
    /// the opponent goal's direction (0.9 rad for the keeper) kicks it on
    /// while the ball is behind this x (m, own goal at -x), instead of
    /// dribbling. -0.5: the scripted team's own half clearance; the half
    /// length: kick it long everywhere.
    pub clear_x: f32,
    /// Reading the ball: above 0, players go where the rolling ball will
    /// be rather than where it is. The player going for it walks to the
    /// ball's place after the time it needs to get there (its distance at
    /// `walk_speed`), at most `lead` seconds ahead; who goes for it, the
    /// support places and the keeper's place follow the ball `lead` seconds
    /// ahead. The ball rolls with its speed decaying as
    /// exp(-`ball_damping` t) (the match configuration's
    /// `ball_linear_damping`). 0: off (s).
    pub lead: f32,
    /// See `lead` (1/s).
    pub ball_damping: f32,
    /// See `lead` (m/s).
    pub walk_speed: f32,
    /// Who goes for the ball: at 1, the field player with the shortest way
    /// to a kick toward the goal, not the nearest one: a player on the
    /// wrong side of the ball counts the walk round behind it (to `behind`
    /// from the ball on its line to the goal, wide of the ball when the
    /// ball is in the way), as `engage` walks it. Between 0 and 1 the two
    /// lengths are mixed. 0: the nearest (off).
    pub engage_path: f32,
    /// Who goes for the ball: metres added to a player's way per radian it
    /// must turn to face where it walks first. 0: off (m/rad).
    pub engage_turn: f32,
}

/// The ladder of built-in teams, weakest first: level `n` is
/// `LEVELS[n - 1]`, a file of `KEY = VAL` lines (assets/scripted/levels/,
/// built into the binary) over the defaults. Level [`DEFAULT_LEVEL`] is
/// the plain scripted team: its file changes nothing.
pub const LEVELS: [&str; 5] = [
    include_str!("../../../../../assets/scripted/levels/level-1.toml"),
    include_str!("../../../../../assets/scripted/levels/level-2.toml"),
    include_str!("../../../../../assets/scripted/levels/level-3.toml"),
    include_str!("../../../../../assets/scripted/levels/level-4.toml"),
    include_str!("../../../../../assets/scripted/levels/level-5.toml"),
];

/// The level that is the plain scripted team (`scripted:3` = `scripted`).
pub const DEFAULT_LEVEL: u8 = 3;

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
            wide_behind: 0.15,
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
            react_ticks: 1.0,
            hold_turns: 1.0,
            aimed_pass: 0.0,
            aim_offset: 0.0,
            keeper_guard: 0.0,
            markers: 0.0,
            mark_gap: 0.5,
            mark_range: 3.5,
            set_play_guard: 0.0,
            keep_out: 0.7,
            set_play_pass: 0.0,
            set_play_wait: 8.0,
            shot_line: 0.0,
            shot_margin: 0.3,
            clear_x: -0.5,
            lead: 0.0,
            ball_damping: 0.8,
            walk_speed: 0.2,
            engage_path: 0.0,
            engage_turn: 0.0,
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

    /// Level `n` of the ladder ([`LEVELS`], 1 = the weakest) on the
    /// default pitch.
    pub fn level(n: u8) -> Result<ScriptedParams, String> {
        let text = usize::from(n)
            .checked_sub(1)
            .and_then(|i| LEVELS.get(i))
            .ok_or_else(|| format!("no level {n}: the levels are 1 to {}", LEVELS.len()))?;
        let p = toml::from_str::<ScriptedParams>(text).map_err(|e| format!("level {n}: {e}"))?;
        p.validate().map_err(|e| format!("level {n}: {e}"))?;
        Ok(p)
    }

    /// Level `n` on `pitch`, as [`ScriptedParams::for_pitch`] adapts the
    /// defaults (a level changes no pitch size). A level that sets its own
    /// `b_rad` keeps it, as it does under `eval` and `match`.
    pub fn level_for_pitch(n: u8, pitch: &Pitch) -> Result<ScriptedParams, String> {
        let on_pitch = ScriptedParams::for_pitch(pitch);
        let level = ScriptedParams::level(n)?;
        let b_rad = if level.b_rad == ScriptedParams::default().b_rad {
            on_pitch.b_rad
        } else {
            level.b_rad
        };
        Ok(ScriptedParams {
            half_length: on_pitch.half_length,
            goal_half_width: on_pitch.goal_half_width,
            b_rad,
            ..level
        })
    }

    /// The field names, alphabetically.
    pub fn keys() -> Vec<String> {
        match serde_json::to_value(ScriptedParams::default()) {
            Ok(serde_json::Value::Object(m)) => m.keys().cloned().collect(),
            _ => Vec::new(),
        }
    }

    /// Parses what follows `scripted:` in a policy spec: `KEY=VAL,KEY=VAL`
    /// (the fields of this struct, in metres and radians), the path of a
    /// TOML file (ending in `.toml`) holding `KEY = VAL` lines, or a level
    /// of the ladder, `N` or `N,KEY=VAL,...` (level `N`'s parameters with
    /// those changed). Fields not named keep their defaults (a level's
    /// values); unknown keys, numbers that do not parse and values that
    /// make no sense (see [`ScriptedParams::validate`]) are errors that say
    /// which.
    pub fn parse_spec(spec: &str) -> Result<ScriptedParams, String> {
        let (head, rest) = match spec.split_once(',') {
            Some((head, rest)) => (head, Some(rest)),
            None => (spec, None),
        };
        let p = if !head.is_empty() && head.trim().bytes().all(|b| b.is_ascii_digit()) {
            let n = head
                .trim()
                .parse::<u8>()
                .map_err(|_| format!("no level {head}: the levels are 1 to {}", LEVELS.len()))?;
            let base = ScriptedParams::level(n)?;
            match rest {
                Some(rest) => base.with_spec(rest)?,
                None => base,
            }
        } else if spec.ends_with(".toml") {
            let text = std::fs::read_to_string(spec).map_err(|e| format!("reading {spec}: {e}"))?;
            toml::from_str::<ScriptedParams>(&text).map_err(|e| format!("{spec}: {e}"))?
        } else {
            ScriptedParams::default().with_spec(spec)?
        };
        p.validate()?;
        Ok(p)
    }

    /// These parameters with `KEY=VAL,...` changed.
    fn with_spec(self, spec: &str) -> Result<ScriptedParams, String> {
        let mut map = match serde_json::to_value(self) {
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
        serde_json::from_value(serde_json::Value::Object(map)).map_err(|e| e.to_string())
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
            ("ball_damping", self.ball_damping),
            ("walk_speed", self.walk_speed),
        ];
        let non_negative = [
            ("reach_min", self.reach_min),
            ("align_tolerance", self.align_tolerance),
            ("behind", self.behind),
            ("wide_behind", self.wide_behind),
            ("keeper_zone", self.keeper_zone),
            ("contest_radius", self.contest_radius),
            ("turn_stop", self.turn_stop),
            ("support_ahead", self.support_ahead),
            ("cover_behind", self.cover_behind),
            ("aim_offset", self.aim_offset),
            ("keeper_guard", self.keeper_guard),
            ("mark_gap", self.mark_gap),
            ("mark_range", self.mark_range),
            ("keep_out", self.keep_out),
            ("set_play_wait", self.set_play_wait),
            ("shot_line", self.shot_line),
            ("shot_margin", self.shot_margin),
            ("lead", self.lead),
            ("engage_path", self.engage_path),
            ("engage_turn", self.engage_turn),
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
        if !self.clear_x.is_finite() {
            return Err(format!(
                "clear_x must be a finite number, got {}",
                self.clear_x
            ));
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
        if !(self.react_ticks >= 1.0
            && self.react_ticks <= 100.0
            && self.react_ticks.fract() == 0.0)
        {
            return Err(format!(
                "react_ticks must be a whole number from 1 to 100, got {}",
                self.react_ticks
            ));
        }
        for (k, v, max) in [
            ("markers", self.markers, 2.0),
            ("set_play_guard", self.set_play_guard, 3.0),
            ("set_play_pass", self.set_play_pass, 1.0),
            ("hold_turns", self.hold_turns, 1.0),
            ("aimed_pass", self.aimed_pass, 1.0),
        ] {
            if !(v >= 0.0 && v <= max && v.fract() == 0.0) {
                return Err(format!(
                    "{k} must be a whole number from 0 to {max}, got {v}"
                ));
            }
        }
        if self.aim_offset >= self.goal_half_width {
            return Err(format!(
                "aim_offset ({}) must be inside the goal, below goal_half_width ({})",
                self.aim_offset, self.goal_half_width
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
