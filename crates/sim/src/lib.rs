//! Physics of a naosoccer pitch on rapier3d: the ground, two goals with posts,
//! crossbar and net, the ball, and eight NAO robots built from `assets/nao.urdf`.
//!
//! `sim` knows nothing of rules, teams, sockets or learning: it steps physics
//! with a fixed time step and answers questions about bodies. Robot `i` of the
//! eight is just an index here; the referee decides what it means.
//!
//! API CONTRACT (used by referee, server, learn; keep these signatures):
//! ```ignore
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
//!     pub fn place_ball(&mut self, x: f32, y: f32);             // at rest on the ground
//!     pub fn set_ball_velocity(&mut self, vx: f32, vy: f32);
//!     pub fn place_robot(&mut self, robot: usize, x: f32, y: f32, heading: f32); // upright, at rest
//!     pub fn stand_up(&mut self, robot: usize);                 // upright where it lies, same heading
//!     pub fn push_robot(&mut self, robot: usize, impulse: [f32; 3]); // at torso height
//!     pub fn state_hash(&self) -> u64;                          // raw bits of every body's pose+velocity, sim RNG state
//! }
//! pub struct Snapshot { pub step: u64, pub ball: BallState, pub robots: [RobotState; 8], pub kicks: Vec<Kick> /* this step */ }
//! pub struct BallState { pub pos: [f32; 3], pub vel: [f32; 3] }
//! pub struct RobotState { pub pos: [f32; 3] /* torso */, pub heading: f32, pub tilt: f32, pub vel: [f32; 3],
//!                         pub fallen: bool /* balance lost, lying */, pub kicking: bool, pub last_ball_touch_step: Option<u64> }
//! pub struct Kick { pub robot: usize, pub speed: f32 }      // a kick that moved the ball
//! ```
