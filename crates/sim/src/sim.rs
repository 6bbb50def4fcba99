//! `Sim`: the world of `world.rs` plus the robots' controllers (gait, kick,
//! balance), fall detection and the snapshot.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rapier3d::math::{Pose, Rot3, Vec3};
use rapier3d::prelude::{ColliderHandle, ColliderSet, PhysicsWorld, RigidBody, RigidBodyHandle};

use crate::hash::StateHasher;
use crate::place::{body_reach, free_spot, is_clear, Area, CLEARANCE};
use crate::world::{
    build, default_robot_spot, set_sole_friction, standing_pose, tilt_of, ROBOT_TAG,
};
use crate::{
    BallState, Command, Kick, RobotModel, RobotState, SimConfig, SimError, Snapshot, ROBOTS,
};

mod stage;

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
    command: Command,
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
            command: Command::Stay,
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
    pub fn set_command(&mut self, robot: usize, cmd: Command) {
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

    /// One physics step of `dt`:
    ///
    /// - gait noise is redrawn every `gait_noise_period` (robot order);
    /// - each standing robot's legs push with a horizontal force, applied at
    ///   the ground under its centre of mass and capped at `drive_force`,
    ///   toward its target velocity (`forward`: heading x walk speed, else
    ///   zero); a capped yaw torque tracks its target yaw rate (turns, or the
    ///   drift while walking); a capped upright torque resists tilt;
    /// - a robot walking against another (held under half its speed with
    ///   another torso within `stumble_distance` ahead) stumbles with
    ///   probability `dt / stumble_time` a step: its controller lets go and a
    ///   torque throws it over (see `stumble_torque`);
    /// - a fallen robot is passive: no force or torque of its own acts on it,
    ///   only gravity and contacts;
    /// - a kick strikes once its wind-up is over: the ball is hit only if its
    ///   centre lies within the kick's reach in front of the robot, and then
    ///   as by a foot swung at it (see `SimConfig::kick_speed`);
    /// - rapier steps (the ball swept against every collider, robots
    ///   included, so a fast ball cannot skip through a shin); a robot tilted
    ///   past `fall_tilt` has fallen; a slow ball on the ground stops.
    pub fn step(&mut self) {
        self.snapshot.kicks.clear();
        if self.steps % self.noise_period_steps == 0 {
            self.draw_gait_noise();
        }
        let cfg = &self.cfg;
        let dt = cfg.dt;
        let mut at = [Vec3::ZERO; ROBOTS];
        for (p, h) in at.iter_mut().zip(&self.robots) {
            *p = self.world.bodies[*h].translation();
        }
        for i in 0..ROBOTS {
            let c = &mut self.ctrl[i];
            let body = &mut self.world.bodies[self.robots[i]];
            body.reset_forces(false);
            body.reset_torques(false);
            self.strikes[i] = false;
            let ccd = if c.fallen || c.stumble.is_some() {
                FALL_CCD
            } else {
                0.0
            };
            if body.soft_ccd_prediction() != ccd {
                body.set_soft_ccd_prediction(ccd);
            }
            if let Some((x, y, since)) = c.stumble {
                // Throw the body over until it is well past its balance
                // limit, or give up after a second: held up by whatever it
                // leant on, it caught itself if it never tilted past
                // `fall_tilt`, and its controller takes over again.
                let w = body.angvel();
                if tilt_of(body.rotation()) < 2.0 * cfg.fall_tilt
                    && self.steps - since < self.stumble_steps
                {
                    // It starts the fall; gravity finishes it. Pushed on
                    // to twice `fall_tilt`, a robot somersaulted at 11 rad/s
                    // and came down on the ball hard enough to bury it.
                    if Vec3::new(w.x, w.y, 0.0).length() < STUMBLE_RATE {
                        let axis = Vec3::Z.cross(Vec3::new(x, y, 0.0));
                        body.add_torque(axis * cfg.stumble_torque, true);
                    }
                } else {
                    c.stumble = None;
                }
                continue;
            }
            if c.fallen {
                continue;
            }
            if c.kick_phase.is_none() && matches!(c.command, Command::Shoot | Command::Pass) {
                c.kick_phase = Some(0);
                c.kick_aim = match c.command {
                    Command::Pass => c.pass_target,
                    _ => None,
                };
            }
            let (target_v, target_w) = match (c.kick_phase, c.command) {
                (Some(_), _) => (0.0, 0.0),
                (None, Command::Forward) => (cfg.walk_speed * c.speed_factor, c.drift),
                (None, Command::TurnLeft) => (0.0, cfg.turn_speed),
                (None, Command::TurnRight) => (0.0, -cfg.turn_speed),
                (None, Command::Stay | Command::Shoot | Command::Pass) => (0.0, 0.0),
            };
            if let Some(phase) = c.kick_phase.as_mut() {
                *phase += 1;
                if *phase == self.windup_steps {
                    self.strikes[i] = true;
                }
                if *phase >= self.kick_steps {
                    c.kick_phase = None;
                }
            }
            // The legs push and balance through the ground only: a robot
            // standing on another robot (or on a roller, or the ball) gets
            // no drive force or upright torque, and one that stays up there
            // for `LIFT_TIME` has lost its balance and stumbles off.
            let lifted =
                sole_height(&self.world.colliders, &self.soles, body.position(), i) > LIFT_HEIGHT;
            c.lifted = if lifted { c.lifted + 1 } else { 0 };
            let tripped = c.kick_phase.is_none()
                && c.command == Command::Forward
                && cfg.stumble_time > 0.0
                && obstructed(body, &at, i, target_v, cfg.stumble_distance)
                && self.rng.random::<f32>() < dt / cfg.stumble_time;
            if tripped || c.lifted >= self.lift_steps {
                // The gait stumbles: the controller lets go and the robot
                // topples backward or sideways, away from what blocks it. It
                // has fallen once it tilts past `fall_tilt`, not before.
                let away = self.rng.random_range(-1.2f32..=1.2);
                let h = heading_of(body.rotation()) + std::f32::consts::PI + away;
                c.stumble = Some((h.cos(), h.sin(), self.steps));
                c.lifted = 0;
                continue;
            }
            if lifted {
                continue;
            }
            drive(body, cfg, self.mass, self.yaw_inertia, target_v, target_w);
        }
        // Whether the ball is still on the pitch as the step begins: the
        // narrow phase finds this step's contacts in these positions, and
        // a kick strikes the ball where it lies now.
        let ball_in = self.ball_in_field();
        for i in 0..ROBOTS {
            if self.strikes[i] {
                self.strike(i, ball_in);
            }
        }

        self.world.step();
        self.steps += 1;

        // Fall detection, ball rest and touches, then the snapshot.
        for i in 0..ROBOTS {
            let tilt = tilt_of(self.world.bodies[self.robots[i]].rotation());
            if !self.ctrl[i].fallen && tilt > self.cfg.fall_tilt {
                self.ctrl[i].fallen = true;
                self.ctrl[i].kick_phase = None;
                set_sole_friction(&mut self.world, &self.cfg, &self.soles, i, true);
            }
        }
        let r = self.cfg.ball_radius;
        let rest = self.cfg.ball_rest_speed;
        let ball = &mut self.world.bodies[self.ball];
        if ball.translation().z < r * 1.1 && ball.linvel().length() < rest && ball.is_moving() {
            ball.set_linvel(Vec3::ZERO, false);
            ball.set_angvel(Vec3::ZERO, false);
        }
        let step = self.steps;
        // A ball wholly beyond the lines has left the pitch: a robot standing
        // out there that it hits afterwards (within the same control tick,
        // before the referee sees the ball out) did not touch it last (audit,
        // seed 4 tick 4646: red's corner kick crossed the goal line, hit a
        // blue robot behind it, and red got another corner).
        let touches = self
            .world
            .narrow_phase
            .contact_pairs_with(self.ball_collider)
            .filter(|_| ball_in);
        let near = self.cfg.contact_prediction;
        for pair in touches {
            // Within the contact prediction, not merely predicted: a falling
            // robot's soft CCD predicts contacts centimetres ahead.
            let touching = pair.has_any_active_contact()
                && pair
                    .manifolds()
                    .iter()
                    .any(|m| m.points.iter().any(|p| p.dist <= near));
            if !touching {
                continue;
            }
            let other = if pair.collider1 == self.ball_collider {
                pair.collider2
            } else {
                pair.collider1
            };
            if let Some(co) = self.world.colliders.get(other) {
                let tag = co.user_data;
                if tag & ROBOT_TAG != 0 {
                    let i = (tag & 0xff) as usize;
                    if i < ROBOTS {
                        self.ctrl[i].last_touch = Some(step);
                    }
                }
            }
        }
        self.refresh_snapshot();
    }

    /// Puts the ball at rest on the ground at the free spot nearest
    /// `(x, y)` (see [`Sim::place_all`] for "free") within the field lines,
    /// and returns the spot used.
    pub fn place_ball(&mut self, x: f32, y: f32) -> (f32, f32) {
        let spot = self.ball_spot((x, y), &self.robots);
        self.put_ball(spot);
        self.refresh_snapshot();
        spot
    }

    /// Sets the ball rolling on the ground at `(vx, vy)` m/s.
    pub fn set_ball_velocity(&mut self, vx: f32, vy: f32) {
        let ball = &mut self.world.bodies[self.ball];
        let v = Vec3::new(vx, vy, 0.0);
        ball.set_linvel(v, true);
        self.refresh_snapshot();
    }

    /// Stands robot `robot` upright at rest facing `heading` at the free spot
    /// nearest `(x, y)` within the field lines plus half the ground margin,
    /// and returns the spot used; clears a fall, a stumble and any kick in
    /// progress.
    pub fn place_robot(&mut self, robot: usize, x: f32, y: f32, heading: f32) -> (f32, f32) {
        let blockers = self.others_than(robot);
        let spot = self.robot_spot(robot, (x, y), heading, &blockers);
        self.put_robot(robot, spot, heading);
        self.refresh_snapshot();
        spot
    }

    /// [`Sim::place_robot`], but only onto spots whose centre is at least
    /// `radius` from `centre` (a set play's keep-out circle): the free spot
    /// outside the circle nearest `(x, y)`, within the field lines plus half
    /// the ground margin.
    pub fn place_robot_outside(
        &mut self,
        robot: usize,
        (x, y): (f32, f32),
        heading: f32,
        centre: (f32, f32),
        radius: f32,
    ) -> (f32, f32) {
        let blockers = self.others_than(robot);
        let outside = |cx: f32, cy: f32| (cx - centre.0).hypot(cy - centre.1) >= radius;
        let spot = self.robot_spot_where(robot, (x, y), heading, &blockers, outside);
        self.put_robot(robot, spot, heading);
        self.refresh_snapshot();
        spot
    }

    /// Puts the ball at rest on the ground exactly at `(x, y)` (a set
    /// play's spot) and stands every robot whose colliders come within 2 cm
    /// of it, standing or lying, upright at the free spot nearest where its
    /// torso was (see [`Sim::place_all`] for "free"), keeping its heading.
    /// Returns which robots were moved, by index.
    pub fn place_ball_exact(&mut self, x: f32, y: f32) -> [bool; ROBOTS] {
        self.put_ball((x, y));
        let mut moved = [false; ROBOTS];
        for (i, m) in moved.iter_mut().enumerate() {
            let body = &self.world.bodies[self.robots[i]];
            let pose = *body.position();
            let reach = body_reach(&self.world, self.robots[i]);
            if is_clear(
                &self.world,
                self.robots[i],
                reach,
                &pose,
                &[self.ball],
                &[],
                CLEARANCE,
            ) {
                continue;
            }
            let t = pose.translation;
            let heading = heading_of(&pose.rotation);
            let blockers = self.others_than(i);
            let spot = self.robot_spot(i, (t.x, t.y), heading, &blockers);
            self.put_robot(i, spot, heading);
            *m = true;
        }
        self.refresh_snapshot();
        moved
    }

    /// Stands robot `robot` upright at rest where it lies (torso x, y),
    /// keeping its heading, or at the nearest free spot if that is taken;
    /// returns the spot used.
    pub fn stand_up(&mut self, robot: usize) -> (f32, f32) {
        let body = &self.world.bodies[self.robots[robot]];
        let t = body.translation();
        let heading = heading_of(body.rotation());
        self.place_robot(robot, t.x, t.y, heading)
    }

    /// Puts everything in place at once (a kick-off): the ball at rest at the
    /// free spot nearest `ball`, then robot 0, 1, ... upright at rest at the
    /// free spot nearest its `(x, y)`, facing its heading. Each body keeps
    /// clear of those put before it in this call; bodies not yet moved do not
    /// block. Returns the spots used.
    ///
    /// "Free" everywhere in the placement API: every collider of the body
    /// keeps 2 cm from every collider of the bodies that block and of the
    /// goals (lying robots included). The search is deterministic: the asked
    /// spot, then rings 5 cm apart around it, each walked counter-clockwise
    /// from +x, the first clear candidate inside the allowed area winning.
    /// The ball stays within the field lines, robots within the lines plus
    /// half the ground margin.
    pub fn place_all(
        &mut self,
        ball: (f32, f32),
        robots: &[(f32, f32, f32); ROBOTS],
    ) -> ((f32, f32), [(f32, f32); ROBOTS]) {
        let ball_spot = self.ball_spot(ball, &[]);
        self.put_ball(ball_spot);
        let mut spots = [(0.0, 0.0); ROBOTS];
        let mut blockers = [self.ball; ROBOTS + 1];
        for (i, &(x, y, heading)) in robots.iter().enumerate() {
            spots[i] = self.robot_spot(i, (x, y), heading, &blockers[..=i]);
            self.put_robot(i, spots[i], heading);
            blockers[i + 1] = self.robots[i];
        }
        self.refresh_snapshot();
        (ball_spot, spots)
    }

    fn ball_spot(&self, at: (f32, f32), blockers: &[RigidBodyHandle]) -> (f32, f32) {
        let r = self.cfg.ball_radius;
        let area = Area {
            half_x: self.cfg.field_length * 0.5,
            half_y: self.cfg.field_width * 0.5,
        };
        free_spot(
            &self.world,
            self.ball,
            |x, y| Pose::from_translation(Vec3::new(x, y, r)),
            at,
            area,
            |_, _| true,
            blockers,
            &self.goal_colliders,
        )
    }

    fn robot_spot(
        &self,
        robot: usize,
        at: (f32, f32),
        heading: f32,
        blockers: &[RigidBodyHandle],
    ) -> (f32, f32) {
        self.robot_spot_where(robot, at, heading, blockers, |_, _| true)
    }

    /// [`Sim::robot_spot`] among the spots `allowed` accepts.
    fn robot_spot_where(
        &self,
        robot: usize,
        at: (f32, f32),
        heading: f32,
        blockers: &[RigidBodyHandle],
        allowed: impl Fn(f32, f32) -> bool,
    ) -> (f32, f32) {
        let area = Area {
            half_x: (self.cfg.field_length + self.cfg.ground_margin) * 0.5,
            half_y: (self.cfg.field_width + self.cfg.ground_margin) * 0.5,
        };
        let h = self.torso_height;
        free_spot(
            &self.world,
            self.robots[robot],
            |x, y| standing_pose(h, x, y, heading),
            at,
            area,
            allowed,
            blockers,
            &self.goal_colliders,
        )
    }

    /// Every body but robot `robot`: the blockers of its placement.
    fn others_than(&self, robot: usize) -> [RigidBodyHandle; ROBOTS] {
        let mut blockers = [self.ball; ROBOTS];
        for (j, b) in blockers.iter_mut().skip(1).enumerate() {
            *b = self.robots[if j < robot { j } else { j + 1 }];
        }
        blockers
    }

    fn put_ball(&mut self, (x, y): (f32, f32)) {
        let r = self.cfg.ball_radius;
        let ball = &mut self.world.bodies[self.ball];
        ball.set_position(Pose::from_translation(Vec3::new(x, y, r)), true);
        ball.set_linvel(Vec3::ZERO, true);
        ball.set_angvel(Vec3::ZERO, true);
    }

    fn put_robot(&mut self, robot: usize, (x, y): (f32, f32), heading: f32) {
        if !self.in_play(robot) {
            return;
        }
        let pose = standing_pose(self.torso_height, x, y, heading);
        let body = &mut self.world.bodies[self.robots[robot]];
        body.set_position(pose, true);
        body.set_linvel(Vec3::ZERO, true);
        body.set_angvel(Vec3::ZERO, true);
        let c = &mut self.ctrl[robot];
        if c.fallen {
            set_sole_friction(&mut self.world, &self.cfg, &self.soles, robot, false);
        }
        c.fallen = false;
        c.kick_phase = None;
        c.stumble = None;
    }

    /// An impulse (N s, world frame) on robot `robot`'s torso origin.
    pub fn push_robot(&mut self, robot: usize, impulse: [f32; 3]) {
        let body = &mut self.world.bodies[self.robots[robot]];
        let at = body.translation();
        body.apply_impulse_at_point(Vec3::from_array(impulse), at, true);
        self.refresh_snapshot();
    }

    /// Puts robot `robot`'s torso at `pos` (metres) turned by `rotation`
    /// (a unit quaternion `[x, y, z, w]`, world from body), at rest, exactly
    /// there: no search for a free spot, so it may touch or overlap other
    /// bodies. Tilted past `fall_tilt` it lies fallen, its controller off, as
    /// after a fall; otherwise it stands with its controller on. Clears a
    /// stumble and any kick in progress. For staging a situation (a test, a
    /// scenario); restarts use [`Sim::place_robot`], which keeps bodies
    /// apart. Panics if `robot >= ROBOTS`.
    pub fn set_robot_pose(&mut self, robot: usize, pos: [f32; 3], rotation: [f32; 4]) {
        let rot = Rot3::from_array(rotation).normalize();
        let body = &mut self.world.bodies[self.robots[robot]];
        body.set_position(Pose::from_parts(Vec3::from_array(pos), rot), true);
        body.set_linvel(Vec3::ZERO, true);
        body.set_angvel(Vec3::ZERO, true);
        let lying = tilt_of(&rot) > self.cfg.fall_tilt;
        let c = &mut self.ctrl[robot];
        if c.fallen != lying {
            set_sole_friction(&mut self.world, &self.cfg, &self.soles, robot, lying);
        }
        c.fallen = lying;
        c.kick_phase = None;
        c.stumble = None;
        self.refresh_snapshot();
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

    fn draw_gait_noise(&mut self) {
        let (drift, speed) = (self.cfg.gait_drift_rate, self.cfg.gait_speed_noise);
        for c in &mut self.ctrl {
            c.drift = drift * self.rng.random_range(-1.0f32..=1.0);
            c.speed_factor = 1.0 + speed * self.rng.random_range(-1.0f32..=1.0);
        }
    }

    /// Whether the ball is on the pitch: not wholly beyond a touch or goal
    /// line (the field lines of the config; a ball in a goal is beyond).
    fn ball_in_field(&self) -> bool {
        let p = self.world.bodies[self.ball].translation();
        let r = self.cfg.ball_radius;
        p.x.abs() <= self.cfg.field_length * 0.5 + r && p.y.abs() <= self.cfg.field_width * 0.5 + r
    }

    /// The strike of robot `i`'s kick; `ball_in`: the ball is on the pitch
    /// (a kick of a ball that has left it moves it but is no touch).
    fn strike(&mut self, i: usize, ball_in: bool) {
        // Draw first, hit or miss, so the RNG stream does not depend on
        // where the ball happens to be.
        let speed_err = self.rng.random_range(-1.0f32..=1.0);
        let angle_err = self.rng.random_range(-1.0f32..=1.0);
        let cfg = &self.cfg;
        let robot = &self.world.bodies[self.robots[i]];
        let heading = heading_of(robot.rotation());
        let fwd = Vec3::new(heading.cos(), heading.sin(), 0.0);
        let left = Vec3::new(-fwd.y, fwd.x, 0.0);
        let rel = self.world.bodies[self.ball].translation() - robot.translation();
        let (ahead, side) = (rel.dot(fwd), rel.dot(left));
        let ball_z = self.world.bodies[self.ball].translation().z;
        let in_reach = ahead >= cfg.kick_reach_min
            && ahead <= cfg.kick_reach_max
            && side.abs() <= cfg.kick_half_width
            && ball_z < cfg.ball_radius * 2.5;
        if !in_reach {
            return;
        }
        // The foot is swung along the kick direction so that it sends a
        // ball at rest off at the kick speed, and hits like a massive body:
        // the ball's velocity along the swing becomes u + e (u - v_n), its
        // velocity across the swing stays. A ball moving away faster than
        // the foot is not reached.
        let e = cfg.ball_restitution;
        // A pass: toward its target, as fast as a ball slowed only by the
        // linear damping needs to roll PASS_OVERSHOOT past it (never faster
        // than a shot).
        let (speed, aim) = match self.ctrl[i].kick_aim {
            Some([x, y]) => {
                let b = self.world.bodies[self.ball].translation();
                let (dx, dy) = (x - b.x, y - b.y);
                let need = cfg.ball_linear_damping * (dx.hypot(dy) + crate::PASS_OVERSHOOT);
                (need.min(cfg.kick_speed), dy.atan2(dx))
            }
            None => (cfg.kick_speed, heading),
        };
        let foot = speed * (1.0 + cfg.kick_speed_noise * speed_err) / (1.0 + e);
        let dir = aim + cfg.kick_angle_noise * angle_err;
        let n = Vec3::new(dir.cos(), dir.sin(), 0.0);
        let ball = &mut self.world.bodies[self.ball];
        let v = ball.linvel();
        let vn = v.dot(n);
        if vn >= foot {
            return;
        }
        let after = v + n * ((1.0 + e) * (foot - vn));
        ball.set_linvel(after, true);
        let speed = Vec3::new(after.x, after.y, 0.0).length();
        self.snapshot.kicks.push(Kick { robot: i, speed });
        if ball_in {
            self.ctrl[i].last_touch = Some(self.steps + 1);
        }
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

/// The legs: bounded horizontal force toward the target velocity (applied at
/// the ground under the centre of mass, so a braking or pushing robot feels
/// the tipping torque a real one would), bounded yaw torque toward the target
/// yaw rate, bounded upright-keeping torque.
fn drive(
    body: &mut RigidBody,
    cfg: &SimConfig,
    mass: f32,
    yaw_inertia: f32,
    target_speed: f32,
    target_yaw_rate: f32,
) {
    let rot = *body.rotation();
    let heading = heading_of(&rot);
    let target = Vec3::new(heading.cos(), heading.sin(), 0.0) * target_speed;
    let v = body.linvel();
    let err = Vec3::new(target.x - v.x, target.y - v.y, 0.0);
    let force = clamp_len(err * (mass / cfg.drive_time_constant), cfg.drive_force);
    let com = body.center_of_mass();
    body.add_force_at_point(force, Vec3::new(com.x, com.y, 0.0), true);

    let w = body.angvel();
    let yaw = ((target_yaw_rate - w.z) * yaw_inertia / cfg.turn_time_constant)
        .clamp(-cfg.turn_torque, cfg.turn_torque);
    // Rotation taking the body's up axis to the vertical, as an axis-angle.
    let up = rot * Vec3::Z;
    let axis = up.cross(Vec3::Z);
    let s = axis.length();
    let tilt_vec = if s > 1e-6 {
        axis * (up.z.clamp(-1.0, 1.0).acos() / s)
    } else {
        Vec3::ZERO
    };
    let w_h = Vec3::new(w.x, w.y, 0.0);
    let upright = clamp_len(
        tilt_vec * cfg.balance_stiffness - w_h * cfg.balance_damping,
        cfg.balance_torque,
    );
    body.add_torque(upright + Vec3::new(0.0, 0.0, yaw), true);
}

/// Walking but held back (under half the target speed) by another robot
/// close in front.
fn obstructed(body: &RigidBody, at: &[Vec3; ROBOTS], me: usize, target: f32, reach: f32) -> bool {
    let heading = heading_of(body.rotation());
    let fwd = Vec3::new(heading.cos(), heading.sin(), 0.0);
    if body.linvel().dot(fwd) >= 0.5 * target {
        return false;
    }
    let p = at[me];
    at.iter().enumerate().any(|(j, q)| {
        let d = Vec3::new(q.x - p.x, q.y - p.y, 0.0);
        j != me && d.length_squared() < reach * reach && d.dot(fwd) > 0.0
    })
}

/// Height above the ground (z = 0) of robot `robot`'s lowest sole point
/// with its torso at `torso`, metres.
fn sole_height(
    colliders: &ColliderSet,
    soles: &[(usize, ColliderHandle)],
    torso: &Pose,
    robot: usize,
) -> f32 {
    soles
        .iter()
        .filter(|(i, _)| *i == robot)
        .map(|&(_, c)| {
            let co = &colliders[c];
            let at = torso * co.position_wrt_parent().copied().unwrap_or(Pose::IDENTITY);
            co.shape().compute_aabb(&at).mins.z
        })
        .fold(f32::INFINITY, f32::min)
}

fn clamp_len(v: Vec3, max: f32) -> Vec3 {
    let l = v.length();
    if l > max {
        v * (max / l)
    } else {
        v
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
        sim.set_command(0, Command::Forward);
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
        sim.set_command(0, Command::Forward);
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
