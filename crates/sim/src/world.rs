//! Building the rapier world: ground, goals, ball, eight robots. `Sim` and
//! `BareWorld` share this code so the bench floor has exactly the bodies and
//! colliders of a match.

use rapier3d::math::{Pose, Rot3, Vec3};
use rapier3d::prelude::{
    CoefficientCombineRule, ColliderBuilder, ColliderHandle, IntegrationParameters, PhysicsWorld,
    RigidBodyBuilder, RigidBodyHandle, SpringCoefficients,
};

use crate::model::{Primitive, RobotModel};
use crate::{SimConfig, SimError, ROBOTS};

/// How far two touching bodies may move against each other before rapier
/// computes their contacts afresh (metres; see `build`).
const CONTACT_RECYCLE_DISTANCE: f32 = 0.01;

/// Collider `user_data` of a robot part: `ROBOT_TAG | index`.
pub(crate) const ROBOT_TAG: u128 = 1 << 64;

/// A freshly built world and the handles `Sim` needs.
pub(crate) struct Built {
    pub world: PhysicsWorld,
    pub ball: RigidBodyHandle,
    pub ball_collider: ColliderHandle,
    pub robots: [RigidBodyHandle; ROBOTS],
    /// The goals' colliders (posts, bars, nets): fixed obstacles to placement.
    pub goal_colliders: Vec<ColliderHandle>,
    /// Each robot's sole colliders, as (robot, collider).
    pub soles: Vec<(usize, ColliderHandle)>,
}

/// Standing soles slide without friction (the drive force walks the robot);
/// a lying robot's soles rub the ground like the rest of its body, or a
/// robot that fell with some momentum would slide and spin on its heels for
/// ever.
pub(crate) fn set_sole_friction(
    world: &mut PhysicsWorld,
    cfg: &SimConfig,
    soles: &[(usize, ColliderHandle)],
    robot: usize,
    lying: bool,
) {
    for &(_, c) in soles.iter().filter(|(i, _)| *i == robot) {
        let co = &mut world.colliders[c];
        if lying {
            co.set_friction(cfg.robot_friction);
            co.set_friction_combine_rule(CoefficientCombineRule::Average);
        } else {
            co.set_friction(0.0);
            co.set_friction_combine_rule(CoefficientCombineRule::Min);
        }
    }
}

/// Robots line up on their own half, facing the centre, until the referee
/// places them.
pub(crate) fn default_robot_spot(cfg: &SimConfig, i: usize) -> (f32, f32, f32) {
    let side = if i < ROBOTS / 2 { -1.0 } else { 1.0 };
    let k = (i % (ROBOTS / 2)) as f32;
    let x = side * cfg.field_length * 0.25;
    let y = (k - 1.5) * cfg.field_width * 0.2;
    let heading = if side < 0.0 {
        0.0
    } else {
        std::f32::consts::PI
    };
    (x, y, heading)
}

/// The pose of a standing robot's torso at `(x, y)` facing `heading`.
pub(crate) fn standing_pose(torso_height: f32, x: f32, y: f32, heading: f32) -> Pose {
    // A hair above the ground so the soles start in contact, not overlapping.
    Pose::from_parts(
        Vec3::new(x, y, torso_height + 1e-3),
        Rot3::from_rotation_z(heading),
    )
}

pub(crate) fn build(cfg: &SimConfig, model: &RobotModel) -> Result<Built, SimError> {
    cfg.validate()?;
    let mut world = PhysicsWorld::new();
    world.gravity = Vec3::new(0.0, 0.0, -cfg.gravity);
    world.integration_parameters = IntegrationParameters {
        dt: cfg.dt,
        num_solver_iterations: cfg.solver_iterations,
        normalized_prediction_distance: cfg.contact_prediction,
        // rapier reuses a touching pair's contact points until the two
        // bodies have moved 5 cm against each other (its default, made for
        // resting piles). Between two robots that froze a contact for
        // steps while the 3 cm foot rollers slid past it, and the rollers
        // passed through each other (audit: 610 overlaps over 2 cm in 20
        // matches). 1 cm keeps most of the saving of reusing the soles'
        // contacts with the ground (turning reuse off costs a fifth more).
        normalized_contact_recycle_distance: CONTACT_RECYCLE_DISTANCE,
        // Contacts between two moving bodies at rapier's 30 Hz, but
        // critically damped (rapier's damping ratio of 10 is for tall
        // piles): with 10, two robots pushing toe to toe settled 2-3 cm
        // into each other's rollers.
        contact_softness: SpringCoefficients::new(30.0, 1.0),
        ..IntegrationParameters::default()
    };

    // Ground: one thin box whose top face is z = 0. A box (not a half-space)
    // keeps the broad phase from pairing it with every collider in the air.
    let half_x = cfg.field_length * 0.5 + cfg.ground_margin.max(cfg.goal_depth + cfg.net_thickness);
    let half_y = cfg.field_width * 0.5 + cfg.ground_margin;
    let ground = world.insert_body(RigidBodyBuilder::fixed());
    let fixed = |hx: f32, hy: f32, hz: f32, x: f32, y: f32, z: f32| {
        ColliderBuilder::cuboid(hx, hy, hz)
            .translation(Vec3::new(x, y, z))
            .friction(cfg.ground_friction)
    };
    world.insert_collider(fixed(half_x, half_y, 0.05, 0.0, 0.0, -0.05), Some(ground));

    // Goals: posts just behind the goal line, crossbar on top, rigid nets on
    // the back, the sides and the top.
    let p = cfg.goal_post_size * 0.5;
    let t = cfg.net_thickness * 0.5;
    let mouth = cfg.goal_width * 0.5;
    let h = cfg.goal_height;
    let line = cfg.field_length * 0.5;
    let mut goal_colliders = Vec::with_capacity(14);
    for s in [-1.0f32, 1.0] {
        let goal = world.insert_body(RigidBodyBuilder::fixed());
        let mut add = |c: ColliderBuilder| {
            goal_colliders.push(world.insert_collider(c.friction(0.3), Some(goal)));
        };
        for side in [-1.0f32, 1.0] {
            add(fixed(
                p,
                p,
                (h + 2.0 * p) * 0.5,
                s * (line + p),
                side * (mouth + p),
                (h + 2.0 * p) * 0.5,
            ));
            let depth = cfg.goal_depth - 2.0 * p;
            add(fixed(
                depth * 0.5,
                t,
                h * 0.5,
                s * (line + 2.0 * p + depth * 0.5),
                side * (mouth + t),
                h * 0.5,
            ));
        }
        add(fixed(p, mouth + 2.0 * p, p, s * (line + p), 0.0, h + p));
        add(fixed(
            t,
            mouth + 2.0 * t,
            h * 0.5,
            s * (line + cfg.goal_depth + t),
            0.0,
            h * 0.5,
        ));
        add(fixed(
            cfg.goal_depth * 0.5,
            mouth + 2.0 * t,
            t,
            s * (line + cfg.goal_depth * 0.5),
            0.0,
            h + t,
        ));
    }

    let ball = world.insert_body(
        RigidBodyBuilder::dynamic()
            .translation(Vec3::new(0.0, 0.0, cfg.ball_radius))
            .linear_damping(cfg.ball_linear_damping)
            // The ball slides without spin and without friction; rolling
            // resistance is the linear damping. A spinning ball at 3 m/s
            // turns 60 rad/s, more than a radian a step: rapier's contact
            // point, fixed to the ball, then leaves the ground within a step
            // and the ball hops and brakes. Spin plays no part in NAO soccer.
            .lock_rotations()
            // Rapier sweeps fast bodies against fixed colliders (goals,
            // ground) by itself; full CCD also sweeps the ball against the
            // robots, whose shins are thinner than a kick's travel in a step.
            .ccd_enabled(true),
    );
    let ball_collider = world.insert_collider(
        ColliderBuilder::ball(cfg.ball_radius)
            .mass(cfg.ball_mass)
            .friction(0.0)
            .friction_combine_rule(CoefficientCombineRule::Min)
            .restitution(cfg.ball_restitution),
        Some(ball),
    );

    let mut robots = [RigidBodyHandle::invalid(); ROBOTS];
    let mut soles = Vec::new();
    for (i, handle) in robots.iter_mut().enumerate() {
        let (x, y, heading) = default_robot_spot(cfg, i);
        *handle = world.insert_body(
            RigidBodyBuilder::dynamic()
                .pose(standing_pose(model.torso_height(), x, y, heading))
                .additional_mass_properties(model.mass_properties())
                .can_sleep(false),
        );
        let lowest = -model.torso_height();
        for shape in model.collision_shapes() {
            let builder = match shape.primitive {
                Primitive::Cuboid { half_extents } => {
                    ColliderBuilder::cuboid(half_extents.x, half_extents.y, half_extents.z)
                }
                Primitive::Sphere { radius } => ColliderBuilder::ball(radius),
                // URDF cylinders run along z, rapier's along y.
                Primitive::Cylinder {
                    radius,
                    half_length,
                } => ColliderBuilder::cylinder(half_length, radius),
                Primitive::Capsule {
                    radius,
                    half_length,
                } => ColliderBuilder::capsule_z(half_length, radius),
            };
            let pose = match shape.primitive {
                Primitive::Cylinder { .. } => {
                    shape.pose
                        * Pose::from_rotation(Rot3::from_rotation_x(std::f32::consts::FRAC_PI_2))
                }
                _ => shape.pose,
            };
            let (lo, _) = crate::model::z_extent(&shape.primitive, &shape.pose);
            let sole = lo <= lowest + 1e-4;
            let builder = builder
                .position(pose)
                .density(0.0)
                .user_data(ROBOT_TAG | i as u128);
            // Soles slide freely: the legs' bounded drive force stands in for
            // the ground reaction of walking (see `Sim::step`). A fallen
            // robot's soles get the friction of the rest of its body back
            // (`set_sole_friction`).
            let builder = if sole {
                builder
                    .friction(0.0)
                    .friction_combine_rule(CoefficientCombineRule::Min)
            } else {
                builder.friction(cfg.robot_friction)
            };
            let c = world.insert_collider(builder, Some(*handle));
            if sole {
                soles.push((i, c));
            }
        }
    }

    // Mass properties are otherwise only computed by the first step; an
    // impulse before it (a push right after set-up) would have no effect.
    for h in robots.iter().chain([&ball]) {
        let colliders = &world.colliders;
        world.bodies[*h].recompute_mass_properties_from_colliders(colliders);
    }

    Ok(Built {
        world,
        ball,
        ball_collider,
        robots,
        goal_colliders,
        soles,
    })
}

/// Seconds of one walk / turn / stand cycle of a bare-world robot.
const BARE_CYCLE: f32 = 6.0;

/// Seconds between two new headings of a bare-world robot.
const BARE_NEW_HEADING_PERIOD: f32 = 10.0;

/// Seconds between two kicks of the bare world's ball.
const BARE_BALL_PERIOD: f32 = 12.0;

/// Turns by it never repeat a direction.
const GOLDEN_ANGLE: f32 = 2.399_963;

/// Yaw rates (rad/s) the bare world's robots walk at, one a robot: turning
/// both ways, on circles from about 0.6 m to 1.7 m across at the default
/// walk speed, so neighbours' paths cross and the wide ones reach the other
/// half.
const BARE_YAW_RATES: [f32; ROBOTS] = [0.30, -0.12, 0.22, -0.18, 0.18, -0.22, 0.12, -0.30];

/// The bench floor: the very bodies and colliders of a match, with the same
/// rapier settings, moved about as much as a match moves them but by the
/// cheapest possible driving, so that "match / floor" is the price of the
/// controllers, rules, observations and policies, not of contacts the floor
/// never makes.
///
/// What one [`BareWorld::step`] does, straight through rapier's body API
/// (velocities and poses set, no forces):
/// - each robot runs a six-second cycle, staggered robot by robot: two
///   seconds walking at `walk_speed` along its heading while yawing at a
///   fixed rate of its own (so robots walk arcs of circles across the pitch
///   and meet now and then), two seconds turning on the spot at
///   `turn_speed` (left and right by turns), two seconds standing. Roll and
///   pitch rates are zeroed, the vertical velocity is left to gravity and
///   contacts;
/// - every ten seconds, staggered, a robot is stood upright and turned by
///   the golden angle: without it two robots that walk into each other push
///   forever, a clinch no match holds for long (there the blocked robot
///   stumbles, or the ball moves on);
/// - a robot past a touch or goal line is turned to face the centre spot;
/// - every twelve seconds the ball is sent off at 2 m/s in a direction that
///   turns by the golden angle each time; a ball past a line is put back on
///   the centre spot at rest;
/// - rapier steps once.
///
/// The cycle and the ball's period are set so that the floor moves as much
/// as a scripted 4v4 match does: robots average about 0.07 m/s over a match
/// in both, the ball 0.14 to 0.2 m/s. The match's robots crowd the ball, so
/// have another within 0.3 m more often than the floor's (about 70% of
/// ticks against 10-15%); the floor errs on the cheap side there.
///
/// No controllers (no balance, kicks or falls), no snapshot, no RNG, no
/// rules. A floor whose robots stood still would be far too cheap to compare
/// with: rapier reuses resting bodies' contacts, and walking robots cost over
/// twice as much to step as standing ones.
pub struct BareWorld {
    world: PhysicsWorld,
    ball: RigidBodyHandle,
    robots: [RigidBodyHandle; ROBOTS],
    walk_speed: f32,
    half_length: f32,
    half_width: f32,
    ball_radius: f32,
    ball_period: u64,
    turn_period: u64,
    cycle: u64,
    turn_speed: f32,
    steps: u64,
}

impl BareWorld {
    /// Builds the same world as [`crate::Sim::new`].
    pub fn new(cfg: &SimConfig, model: &RobotModel) -> Result<BareWorld, SimError> {
        let built = build(cfg, model)?;
        Ok(BareWorld {
            world: built.world,
            ball: built.ball,
            robots: built.robots,
            walk_speed: cfg.walk_speed,
            half_length: cfg.field_length * 0.5,
            half_width: cfg.field_width * 0.5,
            ball_radius: cfg.ball_radius,
            ball_period: ((BARE_BALL_PERIOD / cfg.dt).round() as u64).max(1),
            turn_period: ((BARE_NEW_HEADING_PERIOD / cfg.dt).round() as u64).max(1),
            cycle: ((BARE_CYCLE / cfg.dt).round() as u64).max(3),
            turn_speed: cfg.turn_speed,
            steps: 0,
        })
    }

    /// Drives the robots and the ball as described above, then one physics
    /// step of the configured `dt`.
    pub fn step(&mut self) {
        let (hl, hw) = (self.half_length, self.half_width);
        let turn_period = self.turn_period;
        let cycle = self.cycle;
        for (i, (h, yaw_rate)) in self.robots.iter().zip(BARE_YAW_RATES).enumerate() {
            let body = &mut self.world.bodies[*h];
            let p = body.translation();
            let fwd = *body.rotation() * Vec3::X;
            let mut heading = fwd.y.atan2(fwd.x);
            let out = p.x.abs() > hl || p.y.abs() > hw;
            let new_heading =
                (self.steps + i as u64 * turn_period / ROBOTS as u64) % turn_period == 0;
            if out || new_heading {
                heading = if out {
                    (-p.y).atan2(-p.x)
                } else {
                    heading + GOLDEN_ANGLE
                };
                body.set_rotation(Rot3::from_rotation_z(heading), true);
            }
            // Walk, turn on the spot, stand: a third of the cycle each.
            let t = self.steps + i as u64 * cycle / ROBOTS as u64;
            let phase = t % cycle;
            // Turns on the spot alternate left and right, so that they do
            // not curl the walk into a small loop.
            let turn = if (t / cycle) % 2 == 0 {
                self.turn_speed
            } else {
                -self.turn_speed
            };
            let (speed, yaw_rate) = match 3 * phase / cycle {
                0 => (self.walk_speed, yaw_rate),
                1 => (0.0, turn),
                _ => (0.0, 0.0),
            };
            let (s, c) = heading.sin_cos();
            let vz = body.linvel().z;
            body.set_linvel(Vec3::new(c * speed, s * speed, vz), true);
            body.set_angvel(Vec3::new(0.0, 0.0, yaw_rate), true);
        }
        let ball = &mut self.world.bodies[self.ball];
        let p = ball.translation();
        if p.x.abs() > hl || p.y.abs() > hw {
            ball.set_position(
                Pose::from_translation(Vec3::new(0.0, 0.0, self.ball_radius)),
                true,
            );
            ball.set_linvel(Vec3::ZERO, true);
        } else if self.steps % self.ball_period == 0 {
            let a = (self.steps / self.ball_period) as f32 * GOLDEN_ANGLE;
            ball.set_linvel(Vec3::new(a.cos(), a.sin(), 0.0) * 2.0, true);
        }
        self.world.step();
        self.steps += 1;
    }

    /// Physics step, seconds.
    pub fn dt(&self) -> f32 {
        self.world.integration_parameters.dt
    }

    /// Rigid bodies and colliders in the world (the same as `Sim`'s).
    pub fn counts(&self) -> (usize, usize) {
        (self.world.bodies.len(), self.world.colliders.len())
    }

    /// Physics steps taken.
    pub fn steps(&self) -> u64 {
        self.steps
    }

    /// The ball's centre, metres.
    pub fn ball_position(&self) -> [f32; 3] {
        self.world.bodies[self.ball].translation().to_array()
    }

    /// Each robot's torso position (metres) and tilt from upright (rad).
    pub fn robot_poses(&self) -> [([f32; 3], f32); ROBOTS] {
        self.robots.map(|h| {
            let body = &self.world.bodies[h];
            (body.translation().to_array(), tilt_of(body.rotation()))
        })
    }

    /// Robot pairs whose colliders touch now (active contacts between two
    /// different robots), for checking that the floor's robots do meet.
    pub fn robot_contacts(&self) -> usize {
        self.world
            .narrow_phase
            .contact_pairs()
            .filter(|pair| {
                if !pair.has_any_active_contact() {
                    return false;
                }
                let tag = |c| self.world.colliders.get(c).map(|co| co.user_data);
                match (tag(pair.collider1), tag(pair.collider2)) {
                    (Some(a), Some(b)) => a & ROBOT_TAG != 0 && b & ROBOT_TAG != 0 && a != b,
                    _ => false,
                }
            })
            .count()
    }
}

/// Angle between a body's up axis and the vertical, radians.
pub(crate) fn tilt_of(rot: &Rot3) -> f32 {
    (*rot * Vec3::Z).z.clamp(-1.0, 1.0).acos()
}
