//! Staging a situation that play alone does not reach (a scenario's start):
//! a robot taken out of play, a robot lying on the pitch, a robot busy in
//! the recovery of a kick, the last touch.
//! Restarts never call these; they keep bodies apart through the placement
//! API of `sim.rs`.

use rapier3d::math::{Rot3, Vec3};

use super::Sim;
use crate::world::standing_pose;

/// Height of a lying robot's torso origin above the ground, metres: on its
/// back, about half the torso's depth.
pub const LYING_HEIGHT: f32 = 0.07;

impl Sim {
    /// Takes robot `robot` out of play for the rest of this sim: it stands
    /// upright at `(x, y)` (anywhere, on the ground or off it) facing
    /// `heading`, and leaves the physics: it neither moves nor collides, no
    /// placement moves it again and its commands do nothing. Panics if
    /// `robot >= ROBOTS`.
    pub fn take_out_of_play(&mut self, robot: usize, x: f32, y: f32, heading: f32) {
        let pose = standing_pose(self.torso_height, x, y, heading);
        let body = &mut self.world.bodies[self.robots[robot]];
        body.set_position(pose, true);
        body.set_linvel(Vec3::ZERO, true);
        body.set_angvel(Vec3::ZERO, true);
        body.set_enabled(false);
        self.set_command(robot, crate::Action::Stay);
        let c = &mut self.ctrl[robot];
        c.kick_phase = None;
        c.stumble = None;
        self.refresh_snapshot();
    }

    /// Whether robot `robot` is in play (not taken out by
    /// [`Sim::take_out_of_play`]).
    pub fn in_play(&self, robot: usize) -> bool {
        self.world.bodies[self.robots[robot]].is_enabled()
    }

    /// Lays robot `robot` on its back at `(x, y)` (its torso), its legs
    /// toward `heading`, at rest: fallen, its controller off, as after a
    /// fall (exactly there: no search for a free spot). Panics if
    /// `robot >= ROBOTS`.
    pub fn lay_down(&mut self, robot: usize, x: f32, y: f32, heading: f32) {
        let rot =
            Rot3::from_rotation_z(heading) * Rot3::from_rotation_y(-std::f32::consts::FRAC_PI_2);
        self.set_robot_pose(robot, [x, y, LYING_HEIGHT], rot.to_array());
    }

    /// Puts standing robot `robot` into the recovery of a kick it has just
    /// made: the strike is past (the ball is not kicked), the robot stands
    /// still and is `kicking` for `kick_recovery` seconds, as after a kick
    /// of its own. A lying or out-of-play robot is left as it is. Panics if
    /// `robot >= ROBOTS`.
    pub fn start_kick_recovery(&mut self, robot: usize) {
        if !self.in_play(robot) || self.ctrl[robot].fallen {
            return;
        }
        let c = &mut self.ctrl[robot];
        c.kick_phase = Some(self.windup_steps);
        c.kick_aim = None;
        self.strikes[robot] = false;
        self.refresh_snapshot();
    }

    /// Makes `robot` the robot that touched the ball last (`None`: nobody
    /// has touched it), as of the current step: a touch record, not a
    /// touch made during the next step.
    pub fn set_last_touch(&mut self, robot: Option<usize>) {
        for (i, c) in self.ctrl.iter_mut().enumerate() {
            c.last_touch = (Some(i) == robot).then_some(self.steps);
        }
        self.refresh_snapshot();
    }
}
