//! Physics of a naosoccer pitch on rapier3d: the ground, two goals with posts,
//! crossbar and net, the ball, and eight NAO robots built from `assets/nao.urdf`.
//!
//! `sim` knows nothing of rules, teams, sockets or learning: it steps physics
//! with a fixed time step and answers questions about bodies. Robot `i` of the
//! eight is just an index here; the referee decides what it means.
//!
//! Frame: x along the field (goals at x = +/- `field_length / 2`), y across,
//! z up, origin at the centre spot on the grass. Headings are yaw angles about
//! +z from +x, radians.
//!
//! Each robot is one dynamic rigid body (the torso frame) whose colliders are
//! the URDF links' collision primitives placed by forward kinematics in the
//! standing pose, and whose mass and inertia are the sum of the URDF link
//! inertias. A gait model drives it with bounded forces (see [`Sim::step`]).
//!
//! The entry points: [`Sim`] (build from a [`SimConfig`] and a
//! [`RobotModel`], set [`Action`]s, `step`, read the [`Snapshot`], place
//! bodies for restarts, `state_hash`), and [`BareWorld`], the same bodies
//! without controllers, the benchmarks' floor.

mod config;
mod hash;
mod model;
mod place;
mod sim;
mod world;

pub use config::SimConfig;
pub use hash::StateHasher;
pub use model::{
    CollisionShape, JointInfo, Primitive, RobotModel, CAPSULE_SUFFIX, NAO_URDF, ROOT_LINK,
    STANDING_POSE,
};
pub use sim::Sim;
pub use world::BareWorld;

use serde::{Deserialize, Serialize};

/// Robots on the pitch: the wire's count, so the two cannot differ (which
/// four are a team is the referee's business).
pub use naosoccer_proto::ROBOTS;

/// What a robot's controller does until told otherwise: the protocol's
/// action, one enum from the wire to the physics (what each does to the
/// body is on its variants).
pub use naosoccer_proto::Action;

/// How far past its target point a `Pass` kick rolls the ball (metres), so
/// that it reaches the receiver still moving.
pub const PASS_OVERSHOOT: f32 = 0.5;

/// Bodies as they are after the last step or placement.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Snapshot {
    /// Physics steps taken since `Sim::new`.
    pub step: u64,
    pub ball: BallState,
    pub robots: [RobotState; ROBOTS],
    /// Kicks that moved the ball in the last step (in robot order).
    pub kicks: Vec<Kick>,
}

/// The ball's centre and velocity, metres and m/s.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct BallState {
    pub pos: [f32; 3],
    pub vel: [f32; 3],
}

/// One robot, read from its body.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct RobotState {
    /// Torso origin, metres (about 0.333 m up when standing).
    pub pos: [f32; 3],
    /// Yaw of the body's forward axis, radians in (-pi, pi]. For a robot
    /// lying down, the direction its body points along the ground.
    pub heading: f32,
    /// Angle between the torso's up axis and the vertical, radians.
    pub tilt: f32,
    /// The torso's full orientation, a unit quaternion `[x, y, z, w]`
    /// (world from body): which way a fallen robot lies.
    pub rotation: [f32; 4],
    /// Torso linear velocity, m/s.
    pub vel: [f32; 3],
    /// Balance lost: the torso tilted past `fall_tilt`. Set in the step in
    /// which the tilt passes it (a stumbling robot, whose controller has
    /// already let go, is not fallen until then), and held, the robot lying
    /// passive with its controller off, until `stand_up` or `place_robot`.
    pub fallen: bool,
    /// In a kick (wind-up or recovery).
    pub kicking: bool,
    /// The last step in which the robot touched the ball (contact or kick)
    /// while the ball was on the pitch: touches of a ball already wholly
    /// beyond a touch or goal line do not count.
    pub last_ball_touch_step: Option<u64>,
    /// The command it holds.
    pub command: Action,
}

/// A kick that moved the ball.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Kick {
    pub robot: usize,
    /// Ball speed imparted, m/s.
    pub speed: f32,
    /// The kick was a `Pass` swung toward a target (`Sim::set_pass_target`),
    /// not along the heading.
    #[serde(default)]
    pub aimed: bool,
}

/// Errors of building a model or a world.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum SimError {
    /// A config value is out of range.
    #[error("invalid sim config: {0}")]
    Config(String),
    /// The URDF does not parse or does not describe a usable robot.
    #[error("invalid robot model: {0}")]
    Urdf(String),
    /// A model file could not be read.
    #[error("cannot read {path}: {source}")]
    Io {
        path: String,
        #[source]
        source: std::io::Error,
    },
}
