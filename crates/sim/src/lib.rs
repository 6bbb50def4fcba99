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
//! API CONTRACT (used by referee, server, learn; keep these signatures):
//! ```text
//! pub struct SimConfig { .. }            // serde Deserialize + Default (paper values), #[serde(default, deny_unknown_fields)]
//! pub struct RobotModel { .. }           // from URDF: RobotModel::from_urdf_str / from_urdf_file / builtin() (include_str! of assets/nao.urdf)
//! pub enum Command { Forward, TurnLeft, TurnRight, Shoot, Stay }
//! pub struct Sim { .. }
//! impl Sim {
//!     pub fn new(cfg: &SimConfig, model: &RobotModel, seed: u64) -> Result<Sim, SimError>;
//!     pub fn dt(&self) -> f32;                                  // physics step, seconds
//!     pub fn set_command(&mut self, robot: usize, cmd: Command);// held until changed
//!     pub fn step(&mut self);                                   // one physics step
//!     pub fn snapshot(&self) -> &Snapshot;                      // refreshed by every step / placement
//!     // Placements go to the nearest spot clear of every body and return it:
//!     pub fn place_ball(&mut self, x: f32, y: f32) -> (f32, f32);  // at rest on the ground
//!     pub fn set_ball_velocity(&mut self, vx: f32, vy: f32);
//!     pub fn place_robot(&mut self, robot: usize, x: f32, y: f32, heading: f32) -> (f32, f32); // upright, at rest
//!     pub fn stand_up(&mut self, robot: usize) -> (f32, f32);    // upright where it lies, same heading
//!     pub fn place_all(&mut self, ball: (f32, f32), robots: &[(f32, f32, f32); 8])
//!         -> ((f32, f32), [(f32, f32); 8]);                     // a kick-off: ball, then robots in order
//!     pub fn push_robot(&mut self, robot: usize, impulse: [f32; 3]); // at torso height
//!     pub fn state_hash(&self) -> u64;                          // raw bits of every body's pose+velocity, sim RNG state
//!     // also: config() -> &SimConfig, seed() -> u64, steps() -> u64, counts() -> (bodies, colliders),
//!     //       default_spot(robot) -> (x, y, heading)
//! }
//! pub struct Snapshot { pub step: u64, pub ball: BallState, pub robots: [RobotState; 8], pub kicks: Vec<Kick> /* this step */ }
//! pub struct BallState { pub pos: [f32; 3], pub vel: [f32; 3] }
//! pub struct RobotState { pub pos: [f32; 3] /* torso */, pub heading: f32, pub tilt: f32,
//!                         pub rotation: [f32; 4] /* quaternion x, y, z, w */, pub vel: [f32; 3],
//!                         pub fallen: bool /* balance lost, lying */, pub kicking: bool, pub last_ball_touch_step: Option<u64>,
//!                         pub command: Command }
//! pub struct Kick { pub robot: usize, pub speed: f32 }      // a kick that moved the ball
//! pub struct BareWorld { .. }  // BareWorld::new(cfg, model) -> Result<_, SimError>; fn step(&mut self): the bench floor
//!                              // (same bodies, robots walked and ball sent by setting velocities; see its docs)
//! ```

mod config;
mod model;
mod place;
mod sim;
mod world;

pub use config::SimConfig;
pub use model::{
    CollisionShape, JointInfo, Primitive, RobotModel, NAO_URDF, ROOT_LINK, STANDING_POSE,
};
pub use sim::Sim;
pub use world::BareWorld;

use serde::{Deserialize, Serialize};

/// Robots on the pitch (4 a team; the referee decides which is which).
pub const ROBOTS: usize = 8;

/// What a robot's controller does until told otherwise: the paper's five
/// actions.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Command {
    /// Walk ahead at `walk_speed` (with gait drift).
    Forward,
    /// Turn on the spot at `turn_speed`, counter-clockwise (heading grows).
    TurnLeft,
    /// Turn on the spot at `turn_speed`, clockwise (heading shrinks).
    TurnRight,
    /// Kick: wind-up, strike, recovery. Once started a kick runs to its end;
    /// while `Shoot` is held the robot kicks again and again.
    Shoot,
    /// Stand still (and resist pushes with the bounded drive force).
    #[default]
    Stay,
}

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
    /// The last step in which the robot touched the ball (contact or kick).
    pub last_ball_touch_step: Option<u64>,
    /// The command it holds.
    pub command: Command,
}

/// A kick that moved the ball.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Kick {
    pub robot: usize,
    /// Ball speed imparted, m/s.
    pub speed: f32,
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
