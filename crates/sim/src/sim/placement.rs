//! Placing bodies: the restarts' search for free spots (see
//! [`Sim::place_all`]), pushes, and exact staging.

use rapier3d::math::{Pose, Rot3, Vec3};
use rapier3d::prelude::RigidBodyHandle;

use super::{heading_of, Sim};
use crate::place::{body_reach, free_spot, is_clear, Area, CLEARANCE};
use crate::world::{set_sole_friction, standing_pose, tilt_of};
use crate::ROBOTS;

impl Sim {
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
}
