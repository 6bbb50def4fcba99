//! `Sim`: the world of `world.rs` plus the robots' controllers (gait, kick,
//! balance), fall detection and the snapshot.
//!
//! This file holds the sim's state, its building, its accessors and its
//! hash; `step.rs` the physics step (controllers, strikes, falls, touches)
//! and `placement.rs` the placement API (restarts, pushes, staging).

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rapier3d::math::{Rot3, Vec3};
use rapier3d::prelude::{ColliderHandle, PhysicsWorld, RigidBody, RigidBodyHandle};

use crate::hash::StateHasher;
use crate::world::{build, default_robot_spot, tilt_of};
use crate::{Action, BallState, RobotModel, RobotState, SimConfig, SimError, Snapshot, ROBOTS};

mod placement;
mod stage;
mod step;

/// A stumbling robot is thrown over only while it tips slower than this,
/// rad/s (a fall from upright under gravity alone reaches about 5 rad/s by
/// the time it lies).
const STUMBLE_RATE: f32 = 2.0;

/// A standing robot whose lowest sole point is more than this above the
/// ground (metres) is off the ground: on another robot, the ball or a
/// roller, not on the grass.
const LIFT_HEIGHT: f32 = 0.01;

/// A robot off the ground this long (seconds) has lost its balance and
/// stumbles (audit: robots stood upright on a lying robot's legs for five
/// seconds, seed 7 tick 726).
const LIFT_TIME: f32 = 0.3;

/// Soft-CCD prediction (metres) of a robot falling or lying: a falling
/// robot's torso moves several centimetres a step, and without predicted
/// contacts two robots falling onto each other overlapped by 5 cm for a
/// tick (audit, seed 6 tick 5665). Standing robots do without: it costs
/// broad-phase work on every body it is set for.
const FALL_CCD: f32 = 0.1;

/// Controller state of one robot.
#[derive(Debug, Clone, Copy)]
struct Ctrl {
    command: Action,
    fallen: bool,
    /// Steps since the kick began, while kicking.
    kick_phase: Option<u32>,
    /// Gait noise drawn every `gait_noise_period`: yaw drift (rad/s) and
    /// speed factor while walking.
    drift: f32,
    speed_factor: f32,
    last_touch: Option<u64>,
    /// A stumble in progress: direction of the fall and the step it began.
    /// The controller is off meanwhile; `fallen` follows once the tilt
    /// passes `fall_tilt` (or never, if the robot catches itself).
    stumble: Option<(f32, f32, u64)>,
    /// Steps in a row the robot has stood off the ground (see
    /// `LIFT_HEIGHT`).
    lifted: u32,
    /// Where a `Pass` kick aims (world frame), as last set.
    pass_target: Option<[f32; 2]>,
    /// The point the kick in progress aims at (a `Pass`), if any.
    kick_aim: Option<[f32; 2]>,
}

impl Default for Ctrl {
    fn default() -> Self {
        Ctrl {
            command: Action::Stay,
            fallen: false,
            kick_phase: None,
            drift: 0.0,
            speed_factor: 1.0,
            last_touch: None,
            stumble: None,
            lifted: 0,
            pass_target: None,
            kick_aim: None,
        }
    }
}

/// A pitch with a ball and eight robots, stepped at a fixed `dt`.
pub struct Sim {
    cfg: SimConfig,
    world: PhysicsWorld,
    ball: RigidBodyHandle,
    ball_collider: ColliderHandle,
    robots: [RigidBodyHandle; ROBOTS],
    goal_colliders: Vec<ColliderHandle>,
    soles: Vec<(usize, ColliderHandle)>,
    ctrl: [Ctrl; ROBOTS],
    rng: ChaCha8Rng,
    seed: u64,
    steps: u64,
    snapshot: Snapshot,
    strikes: [bool; ROBOTS],
    // Derived from the model and config once.
    torso_height: f32,
    mass: f32,
    yaw_inertia: f32,
    windup_steps: u32,
    kick_steps: u32,
    noise_period_steps: u64,
    stumble_steps: u64,
    lift_steps: u32,
}

impl Sim {
    /// Builds the pitch; robots stand on their own halves facing the centre
    /// (robots 0..4 at negative x, 4..8 at positive x), the ball on the centre
    /// spot. `seed` seeds the gait and kick noise of this match.
    pub fn new(cfg: &SimConfig, model: &RobotModel, seed: u64) -> Result<Sim, SimError> {
        let built = build(cfg, model)?;
        let mp = model.mass_properties();
        let yaw_inertia = mp.reconstruct_inertia_matrix().z_axis.z;
        let steps_of = |s: f32| (s / cfg.dt).round() as u32;
        let windup_steps = steps_of(cfg.kick_windup).max(1);
        let mut sim = Sim {
            cfg: cfg.clone(),
            world: built.world,
            ball: built.ball,
            ball_collider: built.ball_collider,
            robots: built.robots,
            goal_colliders: built.goal_colliders,
            soles: built.soles,
            ctrl: [Ctrl::default(); ROBOTS],
            rng: ChaCha8Rng::seed_from_u64(seed),
            seed,
            steps: 0,
            snapshot: Snapshot {
                step: 0,
                ball: BallState::default(),
                robots: [RobotState::default(); ROBOTS],
                kicks: Vec::with_capacity(ROBOTS),
            },
            strikes: [false; ROBOTS],
            torso_height: model.torso_height(),
            mass: mp.mass(),
            yaw_inertia,
            windup_steps,
            kick_steps: windup_steps + steps_of(cfg.kick_recovery),
            noise_period_steps: u64::from(steps_of(cfg.gait_noise_period).max(1)),
            stumble_steps: u64::from(steps_of(1.0).max(1)),
            lift_steps: steps_of(LIFT_TIME).max(1),
        };
        sim.refresh_snapshot();
        Ok(sim)
    }

    /// Physics step, seconds.
    pub fn dt(&self) -> f32 {
        self.cfg.dt
    }

    /// The config this sim was built with.
    pub fn config(&self) -> &SimConfig {
        &self.cfg
    }

    /// The seed of the match noise.
    pub fn seed(&self) -> u64 {
        self.seed
    }

    /// Physics steps taken so far.
    pub fn steps(&self) -> u64 {
        self.steps
    }

    /// Rigid bodies and colliders in the world.
    pub fn counts(&self) -> (usize, usize) {
        (self.world.bodies.len(), self.world.colliders.len())
    }

    /// Where robot `i` stands before anyone places it: (x, y, heading).
    pub fn default_spot(&self, robot: usize) -> (f32, f32, f32) {
        default_robot_spot(&self.cfg, robot)
    }

    /// Sets robot `robot`'s command; it holds until changed. A kick in
    /// progress finishes first; a fallen robot keeps it for after it stands.
    /// Panics if `robot >= ROBOTS`.
    pub fn set_command(&mut self, robot: usize, cmd: Action) {
        self.ctrl[robot].command = cmd;
        self.snapshot.robots[robot].command = cmd;
    }

    /// The point (world frame, metres) robot `robot`'s next `Pass` kick
    /// aims at; `None`: along its heading, as `Shoot`. A kick in progress
    /// keeps the aim it started with. Panics if `robot >= ROBOTS`.
    pub fn set_pass_target(&mut self, robot: usize, target: Option<[f32; 2]>) {
        self.ctrl[robot].pass_target = target;
    }

    /// The last snapshot (after the last step or placement).
    pub fn snapshot(&self) -> &Snapshot {
        &self.snapshot
    }

    /// FNV-1a over the raw bits of every dynamic body's pose and velocity,
    /// the controllers' state and the noise RNG's seed and position. Equal
    /// on the same build for the same config, seed and commands.
    pub fn state_hash(&self) -> u64 {
        let mut h = StateHasher::new();
        h.u64(self.steps);
        let mut body = |b: &RigidBody| {
            let p = b.position();
            h.f32s(&p.translation.to_array());
            h.f32s(&p.rotation.to_array());
            h.f32s(&b.linvel().to_array());
            h.f32s(&b.angvel().to_array());
        };
        body(&self.world.bodies[self.ball]);
        for &r in &self.robots {
            body(&self.world.bodies[r]);
        }
        for c in &self.ctrl {
            h.u64(c.command as u64);
            h.u64(u64::from(c.fallen));
            h.u64(c.kick_phase.map_or(u64::MAX, u64::from));
            h.f32s(&[c.drift, c.speed_factor]);
            h.u64(c.last_touch.unwrap_or(u64::MAX));
            let (x, y, since) = c.stumble.unwrap_or((0.0, 0.0, u64::MAX));
            h.f32s(&[x, y]);
            h.u64(since);
            h.u64(u64::from(c.lifted));
            // Only a pass changes these, so matches without one keep the
            // hashes they had before `Pass` existed.
            for aim in [c.pass_target, c.kick_aim].into_iter().flatten() {
                h.f32s(&aim);
            }
        }
        for b in self.rng.get_seed() {
            h.byte(b);
        }
        let pos = self.rng.get_word_pos();
        h.u64(pos as u64);
        h.u64((pos >> 64) as u64);
        h.finish()
    }

    fn refresh_snapshot(&mut self) {
        self.snapshot.step = self.steps;
        let ball = &self.world.bodies[self.ball];
        self.snapshot.ball = BallState {
            pos: ball.translation().to_array(),
            vel: ball.linvel().to_array(),
        };
        for i in 0..ROBOTS {
            let body = &self.world.bodies[self.robots[i]];
            let c = &self.ctrl[i];
            self.snapshot.robots[i] = RobotState {
                pos: body.translation().to_array(),
                heading: heading_of(body.rotation()),
                tilt: tilt_of(body.rotation()),
                rotation: body.rotation().to_array(),
                vel: body.linvel().to_array(),
                fallen: c.fallen,
                kicking: c.kick_phase.is_some(),
                last_ball_touch_step: c.last_touch,
                command: c.command,
            };
        }
    }
}

/// The direction the body points along the ground: its forward axis, or for
/// a body pitched far over, its up axis (fallen forward) or the reverse of
/// it (fallen backward), blended smoothly.
pub(crate) fn heading_of(rot: &Rot3) -> f32 {
    let fwd = *rot * Vec3::X;
    let up = *rot * Vec3::Z;
    let x = fwd.x - fwd.z * up.x;
    let y = fwd.y - fwd.z * up.y;
    y.atan2(x)
}

/// Issue 12's regressions that need to set a body's state directly (a ball
/// in the air, a spinning body); the rest are in `tests/sim.rs`.
#[cfg(test)]
mod tests {
    use super::*;
    use rapier3d::math::Pose;

    fn lab() -> Sim {
        let model = RobotModel::builtin().unwrap();
        let mut sim = Sim::new(&SimConfig::default(), &model, 1).unwrap();
        sim.place_ball(2.5, 2.0);
        for i in 0..ROBOTS {
            sim.place_robot(i, -2.5 + 0.7 * i as f32, -2.0, 0.0);
        }
        sim.place_robot(0, 0.0, 0.0, 0.0);
        sim
    }

    fn run(sim: &mut Sim, seconds: f32) {
        for _ in 0..sim.config().steps_for(seconds) {
            sim.step();
        }
    }

    /// A ball dropped onto robot 0's feet from many spots (in front of and
    /// behind the shins, beside and between the feet) is on the grass within
    /// 0.5 s of landing: a flat foot held it wedged against the shin for
    /// seconds (audit, seed 2 tick 3916).
    #[test]
    fn issue_12_a_ball_dropped_on_a_foot_ends_on_the_ground() {
        let r = SimConfig::default().ball_radius;
        let mut stuck = Vec::new();
        let mut spots = 0;
        for ix in 0..=32 {
            let x = -0.16 + 0.01 * ix as f32;
            for iy in 0..=12 {
                let y = -0.12 + 0.02 * iy as f32;
                let mut sim = lab();
                let ball = sim.ball;
                // Dropped from 2 cm above a (box) foot's top, unless that
                // spot is inside a leg.
                let at = Pose::from_translation(Vec3::new(x, y, 0.03 + r + 0.02));
                let reach = crate::place::body_reach(&sim.world, ball);
                if !crate::place::is_clear(&sim.world, ball, reach, &at, &sim.robots, &[], 1e-3) {
                    continue;
                }
                spots += 1;
                sim.world.bodies[ball].set_position(at, true);
                // Falling 2 cm takes 0.06 s; then half a second to roll off.
                run(&mut sim, 0.56);
                let b = sim.snapshot().ball;
                if b.pos[2] > r + 0.003 {
                    stuck.push((x, y, b.pos));
                }
            }
        }
        assert!(spots > 40, "only {spots} drop spots");
        assert!(stuck.is_empty(), "balls resting on a foot: {stuck:?}");
    }

    /// A lying robot set spinning and sliding (as a fall with momentum
    /// leaves it) comes to rest within a second and then lies still: its
    /// soles were frictionless, and a robot on its back turned on its heels
    /// for seconds (audit: 17 of 206 fallen robots, seed 16 tick 1259).
    #[test]
    fn issue_12_a_lying_robot_comes_to_rest_and_stays_still() {
        for (push, spin) in [
            ([-12.0, 0.0, 0.0], 2.0),
            ([12.0, 0.0, 0.0], -2.0),
            ([0.0, 12.0, 0.0], 3.0),
        ] {
            let mut sim = lab();
            sim.push_robot(0, push);
            run(&mut sim, 2.0);
            assert!(sim.snapshot().robots[0].fallen);
            let h = sim.robots[0];
            let body = &mut sim.world.bodies[h];
            let v = body.linvel();
            body.set_angvel(Vec3::new(0.0, 0.0, spin), true);
            body.set_linvel(Vec3::new(0.3, 0.1, v.z), true);
            run(&mut sim, 1.0);
            let before = sim.snapshot().robots[0];
            run(&mut sim, 3.0);
            let after = sim.snapshot().robots[0];
            let moved = Vec3::from_array(after.pos) - Vec3::from_array(before.pos);
            let turned =
                Rot3::from_array(before.rotation).angle_between(Rot3::from_array(after.rotation));
            assert!(after.fallen);
            assert!(moved.length() < 0.01, "push {push:?}: slid {moved:?}");
            assert!(turned < 0.02, "push {push:?}: turned {turned} rad");
        }
    }

    /// A stumbling robot's controller is off at once, but it has not fallen
    /// until its torso tilts past `fall_tilt`.
    #[test]
    fn issue_12_a_stumble_is_not_a_fall_until_the_torso_tilts() {
        let mut sim = lab();
        sim.ctrl[0].stumble = Some((-1.0, 0.0, 0));
        sim.set_command(0, Action::Forward);
        let fall_tilt = sim.config().fall_tilt;
        let mut fell_at = None;
        for step in 0..sim.config().steps_for(1.5) {
            sim.step();
            let r = sim.snapshot().robots[0];
            assert_eq!(
                r.fallen,
                fell_at.is_some() || r.tilt > fall_tilt,
                "step {step}"
            );
            if r.fallen && fell_at.is_none() {
                fell_at = Some(step);
            }
        }
        let fell_at = fell_at.expect("the stumble throws it over");
        assert!(fell_at > 0, "fallen in the first step, still upright");
    }

    /// A robot whose stumble is held up (it leans on something and never
    /// tilts past `fall_tilt`) gets its controller back after the stumble's
    /// second: no robot stays uncontrolled without the referee seeing a fall.
    #[test]
    fn issue_12_a_robot_that_catches_itself_walks_again() {
        let cfg = SimConfig {
            stumble_torque: 0.5, // too weak to throw it over
            ..SimConfig::default()
        };
        let model = RobotModel::builtin().unwrap();
        let mut sim = Sim::new(&cfg, &model, 1).unwrap();
        sim.place_ball(2.5, 2.0);
        sim.ctrl[0].stumble = Some((-1.0, 0.0, 0));
        sim.set_command(0, Action::Forward);
        run(&mut sim, 1.0);
        let r = sim.snapshot().robots[0];
        assert!(!r.fallen && r.tilt < cfg.fall_tilt);
        let x0 = r.pos[0];
        run(&mut sim, 2.0);
        let r = sim.snapshot().robots[0];
        assert!(!r.fallen);
        assert!(r.pos[0] - x0 > 0.2, "walked only {} m", r.pos[0] - x0);
    }
}
