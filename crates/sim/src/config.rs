//! Every physical and control parameter of the pitch, in one serde struct.
//!
//! The referee embeds this struct as the `[sim]` table of `assets/match.toml`.
//! Any field left out takes its default; an unknown field is an error.
//! Defaults are the paper's pitch (6.0 x 4.5 m field, 2.6 x 1.0 m goals) and
//! NAO-like gait figures. Frame: x along the field (goals at x = +/-
//! `field_length / 2`), y across, z up, origin at the centre spot on the grass.

use serde::{Deserialize, Serialize};

use crate::SimError;

/// Parameters of the physics world, the gait model, the kick and balance.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SimConfig {
    // --- stepping -------------------------------------------------------
    /// Physics time step, seconds. The referee calls `Sim::step` several
    /// times per control tick (1/30 s and a 10 Hz tick: 3 steps a tick).
    /// 1/30 s is the coarsest step at which every behaviour test passes;
    /// the gains below are stable for it (and for anything finer).
    pub dt: f32,
    /// Velocity solver iterations of rapier per step (1 or 2 suffices for
    /// bodies standing on flat ground; more costs time).
    pub solver_iterations: usize,
    /// Contacts are predicted this far ahead of touching, metres. Larger
    /// values catch fast bodies earlier but make the contact pairs of a
    /// crowd of robots costlier. Fast bodies (a kicked ball) are swept
    /// continuously against the goals and the ground anyway.
    pub contact_prediction: f32,
    /// Gravity, m/s^2 (acting along -z).
    pub gravity: f32,

    // --- pitch ----------------------------------------------------------
    /// Field length between the goal lines, metres (x).
    pub field_length: f32,
    /// Field width between the touch lines, metres (y).
    pub field_width: f32,
    /// Ground beyond the lines on every side, metres. The ground also reaches
    /// under the goals even when they are deeper than this margin. No walls.
    pub ground_margin: f32,
    /// Friction coefficient of the ground against fallen robots (soles and
    /// ball are frictionless: see `drive_force` and `ball_linear_damping`).
    pub ground_friction: f32,

    // --- goals ----------------------------------------------------------
    /// Goal mouth, inner distance between the posts, metres.
    pub goal_width: f32,
    /// Goal depth behind the goal line, metres (back net position).
    pub goal_depth: f32,
    /// Crossbar height, metres (lower edge of the bar).
    pub goal_height: f32,
    /// Square cross-section of posts and crossbar, metres. The posts stand
    /// just behind the goal line (their front face on the line).
    pub goal_post_size: f32,
    /// Thickness of the (rigid) side, back and top nets, metres.
    pub net_thickness: f32,

    // --- ball -----------------------------------------------------------
    /// Ball radius, metres.
    pub ball_radius: f32,
    /// Ball mass, kg.
    pub ball_mass: f32,
    /// Velocity damping of the ball, 1/s: the rolling resistance. The ball
    /// moves without spin or friction, its speed decaying as
    /// exp(-damping * t), so a kick at v rolls about v / damping metres
    /// (3 m/s and 0.8/s: 3.7 m).
    pub ball_linear_damping: f32,
    /// Below this speed (m/s) a ball on the ground is stopped dead: without
    /// it damping would leave it creeping forever.
    pub ball_rest_speed: f32,
    /// Ball restitution (bounciness) against posts, nets and robots, 0..1.
    pub ball_restitution: f32,

    // --- robots: gait ---------------------------------------------------
    /// Target walking speed of `forward`, m/s (NAO: about 0.1-0.2 m/s).
    pub walk_speed: f32,
    /// Target turning rate of `turn_left` / `turn_right`, rad/s.
    pub turn_speed: f32,
    /// Largest horizontal force the legs exert on the ground, N. It drives
    /// walking, braking and resisting pushes, so two robots pressing on each
    /// other stall instead of one shoving through.
    pub drive_force: f32,
    /// Time constant of the speed controller, seconds: the legs close the
    /// gap to the target velocity at `mass / drive_time_constant` N per m/s
    /// (capped at `drive_force`).
    pub drive_time_constant: f32,
    /// Largest yaw torque of the legs, N m (turning and holding heading).
    pub turn_torque: f32,
    /// Time constant of the yaw-rate controller, seconds.
    pub turn_time_constant: f32,
    /// Open-loop walking drifts (the paper's point): while walking, each robot
    /// turns at a random rate drawn uniformly in +/- this bound, rad/s.
    pub gait_drift_rate: f32,
    /// Walking speed error, a fraction: the speed is scaled by a factor drawn
    /// uniformly in 1 +/- this.
    pub gait_speed_noise: f32,
    /// How often the drift rate and speed error are drawn anew, seconds.
    pub gait_noise_period: f32,

    // --- robots: balance ------------------------------------------------
    /// Stiffness of the upright-keeping torque, N m per rad of tilt.
    pub balance_stiffness: f32,
    /// Damping of the upright-keeping torque, N m per rad/s of tilt rate.
    pub balance_damping: f32,
    /// Largest upright-keeping torque, N m. A push or collision that needs
    /// more tips the robot over.
    pub balance_torque: f32,
    /// Balance limit: a robot tilted more than this from upright, rad, has
    /// fallen; its controller switches off and it lies as an obstacle until
    /// `stand_up`.
    pub fall_tilt: f32,
    /// Walking against another robot trips the gait: a robot told `forward`
    /// that makes under half its walking speed with another robot's torso
    /// within `stumble_distance` ahead stumbles and falls after this mean
    /// time, seconds (a seeded random draw each step). 0 turns it off.
    pub stumble_time: f32,
    /// Torso-to-torso distance, metres, within which another robot blocks.
    pub stumble_distance: f32,
    /// Torque that throws a stumbling robot over, N m, applied until it is
    /// tilted twice `fall_tilt` (at most a second), and only while it tips
    /// slower than 2 rad/s: it starts the fall, gravity finishes it. The
    /// robot's controller is off from the stumble on; it has fallen once
    /// its tilt passes `fall_tilt`, and if whatever it leans on holds it
    /// short of that, its controller takes over again after the second.
    pub stumble_torque: f32,
    /// Friction coefficient of robot bodies (not soles: walking is driven by
    /// the bounded leg force, so soles slide freely).
    pub robot_friction: f32,

    // --- robots: kick ---------------------------------------------------
    /// Wind-up of a kick, seconds: from `shoot` to the strike. The robot
    /// stands still meanwhile.
    pub kick_windup: f32,
    /// Recovery after the strike, seconds, before the next command acts.
    pub kick_recovery: f32,
    /// Ball speed a kick imparts, m/s.
    pub kick_speed: f32,
    /// Kick speed error, a fraction: speed scaled by 1 +/- this (uniform).
    pub kick_speed_noise: f32,
    /// Kick direction error, rad: the ball leaves along the robot heading
    /// turned by a uniform angle in +/- this.
    pub kick_angle_noise: f32,
    /// Reach of the kick, metres, measured from the torso origin forward
    /// along the heading to the ball centre: the ball must be at least this
    /// far (ahead of the toes)...
    pub kick_reach_min: f32,
    /// ...and at most this far.
    pub kick_reach_max: f32,
    /// Sideways reach, metres: |lateral offset| of the ball centre from the
    /// robot's forward axis must not exceed this (covers both feet).
    pub kick_half_width: f32,
}

impl Default for SimConfig {
    fn default() -> Self {
        SimConfig {
            dt: 1.0 / 30.0,
            solver_iterations: 1,
            contact_prediction: 0.005,
            gravity: 9.81,
            field_length: 6.0,
            field_width: 4.5,
            ground_margin: 0.5,
            ground_friction: 0.8,
            goal_width: 2.6,
            goal_depth: 1.0,
            goal_height: 0.8,
            goal_post_size: 0.05,
            net_thickness: 0.04,
            ball_radius: 0.05,
            ball_mass: 0.05,
            ball_linear_damping: 0.8,
            ball_rest_speed: 0.03,
            ball_restitution: 0.4,
            walk_speed: 0.2,
            turn_speed: 0.5,
            drive_force: 40.0,
            drive_time_constant: 0.1,
            turn_torque: 2.0,
            turn_time_constant: 0.1,
            gait_drift_rate: 0.06,
            gait_speed_noise: 0.1,
            gait_noise_period: 1.0,
            balance_stiffness: 60.0,
            balance_damping: 4.0,
            balance_torque: 6.0,
            fall_tilt: 0.35,
            stumble_time: 5.0,
            stumble_distance: 0.35,
            stumble_torque: 15.0,
            robot_friction: 0.5,
            kick_windup: 0.4,
            kick_recovery: 0.3,
            kick_speed: 3.0,
            kick_speed_noise: 0.1,
            kick_angle_noise: 0.08,
            kick_reach_min: 0.1,
            kick_reach_max: 0.26,
            kick_half_width: 0.11,
        }
    }
}

impl SimConfig {
    /// Checks that every value makes physical sense; `Sim::new` calls it.
    pub fn validate(&self) -> Result<(), SimError> {
        let positive = [
            ("dt", self.dt),
            ("contact_prediction", self.contact_prediction),
            ("gravity", self.gravity),
            ("field_length", self.field_length),
            ("field_width", self.field_width),
            ("goal_width", self.goal_width),
            ("goal_depth", self.goal_depth),
            ("goal_height", self.goal_height),
            ("goal_post_size", self.goal_post_size),
            ("net_thickness", self.net_thickness),
            ("ball_radius", self.ball_radius),
            ("ball_mass", self.ball_mass),
            ("drive_force", self.drive_force),
            ("drive_time_constant", self.drive_time_constant),
            ("turn_torque", self.turn_torque),
            ("turn_time_constant", self.turn_time_constant),
            ("gait_noise_period", self.gait_noise_period),
            ("balance_torque", self.balance_torque),
            ("fall_tilt", self.fall_tilt),
            ("kick_reach_max", self.kick_reach_max),
            ("kick_half_width", self.kick_half_width),
        ];
        for (name, v) in positive {
            if !(v.is_finite() && v > 0.0) {
                return Err(SimError::Config(format!(
                    "{name} must be a positive number, got {v}"
                )));
            }
        }
        let non_negative = [
            ("ground_margin", self.ground_margin),
            ("ground_friction", self.ground_friction),
            ("ball_linear_damping", self.ball_linear_damping),
            ("ball_rest_speed", self.ball_rest_speed),
            ("ball_restitution", self.ball_restitution),
            ("walk_speed", self.walk_speed),
            ("turn_speed", self.turn_speed),
            ("gait_drift_rate", self.gait_drift_rate),
            ("gait_speed_noise", self.gait_speed_noise),
            ("balance_stiffness", self.balance_stiffness),
            ("balance_damping", self.balance_damping),
            ("robot_friction", self.robot_friction),
            ("stumble_time", self.stumble_time),
            ("stumble_distance", self.stumble_distance),
            ("stumble_torque", self.stumble_torque),
            ("kick_windup", self.kick_windup),
            ("kick_recovery", self.kick_recovery),
            ("kick_speed", self.kick_speed),
            ("kick_speed_noise", self.kick_speed_noise),
            ("kick_angle_noise", self.kick_angle_noise),
            ("kick_reach_min", self.kick_reach_min),
        ];
        for (name, v) in non_negative {
            if !(v.is_finite() && v >= 0.0) {
                return Err(SimError::Config(format!(
                    "{name} must be a non-negative number, got {v}"
                )));
            }
        }
        if self.dt > 0.1 {
            return Err(SimError::Config(format!(
                "dt {} s is too coarse for contact physics (at most 0.1 s)",
                self.dt
            )));
        }
        if self.solver_iterations == 0 {
            return Err(SimError::Config(
                "solver_iterations must be at least 1".into(),
            ));
        }
        if self.kick_reach_min >= self.kick_reach_max {
            return Err(SimError::Config(format!(
                "kick_reach_min ({}) must be below kick_reach_max ({})",
                self.kick_reach_min, self.kick_reach_max
            )));
        }
        if self.gait_speed_noise >= 1.0 || self.kick_speed_noise >= 1.0 {
            return Err(SimError::Config(
                "gait_speed_noise and kick_speed_noise must be below 1".into(),
            ));
        }
        if self.fall_tilt >= std::f32::consts::FRAC_PI_2 {
            return Err(SimError::Config(format!(
                "fall_tilt {} rad must be below pi/2",
                self.fall_tilt
            )));
        }
        Ok(())
    }

    /// Physics steps in `seconds` of play, rounded to the nearest step.
    pub fn steps_for(&self, seconds: f32) -> u64 {
        (seconds / self.dt).round().max(0.0) as u64
    }
}
