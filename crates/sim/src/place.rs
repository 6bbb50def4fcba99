//! Placement onto free ground: the nearest spot where a body, put down as
//! asked, overlaps no other body.
//!
//! The search is deterministic: the asked spot first, then rings of growing
//! radius around it (`RING_STEP` apart), each walked counter-clockwise from
//! +x at about `RING_STEP` spacing; the first candidate inside the allowed
//! area that is clear wins. "Clear" is measured on the real colliders at the
//! bodies' current poses (read from the bodies, so a body moved earlier in
//! the same call counts where it now is): every collider of the placed body
//! keeps `CLEARANCE` from every collider of every blocking body and of the
//! goals. The ground is never a blocker (standing bodies touch it).

use rapier3d::math::Pose;
use rapier3d::parry::bounding_volume::BoundingVolume;
use rapier3d::parry::query;
use rapier3d::prelude::{ColliderHandle, PhysicsWorld, RigidBodyHandle};

/// Gap a placed body keeps from every other body, metres.
pub(crate) const CLEARANCE: f32 = 0.02;

/// Radius step between two rings of candidate spots, metres (and the spacing
/// of candidates along a ring).
pub(crate) const RING_STEP: f32 = 0.05;

/// The rectangle a body's spot must lie in: |x| <= half_x, |y| <= half_y.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Area {
    pub half_x: f32,
    pub half_y: f32,
}

impl Area {
    fn contains(&self, x: f32, y: f32) -> bool {
        x.abs() <= self.half_x && y.abs() <= self.half_y
    }

    pub fn clamp(&self, x: f32, y: f32) -> (f32, f32) {
        (
            x.clamp(-self.half_x, self.half_x),
            y.clamp(-self.half_y, self.half_y),
        )
    }
}

/// The nearest spot to `(x, y)` (clamped into `area`) where `mover`, posed
/// by `pose_at(x, y)`, keeps `CLEARANCE` from every body in `blockers` and
/// every collider in `fixed` (goals), among the spots `allowed` accepts.
/// Falls back to the clamped spot if no candidate in the area is clear (a
/// pitch full of bodies; never seen).
#[allow(clippy::too_many_arguments)]
pub(crate) fn free_spot(
    world: &PhysicsWorld,
    mover: RigidBodyHandle,
    pose_at: impl Fn(f32, f32) -> Pose,
    (x, y): (f32, f32),
    area: Area,
    allowed: impl Fn(f32, f32) -> bool,
    blockers: &[RigidBodyHandle],
    fixed: &[ColliderHandle],
) -> (f32, f32) {
    let (x, y) = area.clamp(x, y);
    let reach = body_reach(world, mover);
    let clear = |cx: f32, cy: f32| {
        is_clear(
            world,
            mover,
            reach,
            &pose_at(cx, cy),
            blockers,
            fixed,
            CLEARANCE,
        )
    };
    if allowed(x, y) && clear(x, y) {
        return (x, y);
    }
    let rings = (2.0 * (area.half_x + area.half_y) / RING_STEP).ceil() as u32;
    for k in 1..=rings {
        let r = k as f32 * RING_STEP;
        let n = ((std::f32::consts::TAU * r / RING_STEP).round() as u32).max(6);
        for j in 0..n {
            let a = std::f32::consts::TAU * j as f32 / n as f32;
            let (cx, cy) = (x + r * a.cos(), y + r * a.sin());
            if area.contains(cx, cy) && allowed(cx, cy) && clear(cx, cy) {
                return (cx, cy);
            }
        }
    }
    (x, y)
}

/// Whether `mover` at `pose` keeps `clearance` from the blockers (bodies at
/// their current poses) and the `fixed` colliders. `reach` is
/// [`body_reach`] of the mover.
pub(crate) fn is_clear(
    world: &PhysicsWorld,
    mover: RigidBodyHandle,
    reach: f32,
    pose: &Pose,
    blockers: &[RigidBodyHandle],
    fixed: &[ColliderHandle],
    clearance: f32,
) -> bool {
    let movers = &world.bodies[mover];
    let clear_of = |m_pose: &Pose, m: ColliderHandle, o_pose: &Pose, o: ColliderHandle| {
        let (m, o) = (&world.colliders[m], &world.colliders[o]);
        let m_box = m.shape().compute_aabb(m_pose).loosened(clearance);
        if !m_box.intersects(&o.shape().compute_aabb(o_pose)) {
            return true;
        }
        query::distance(m_pose, m.shape(), o_pose, o.shape()).is_ok_and(|d| d.distance >= CLEARANCE)
    };
    for &mc in movers.colliders() {
        let m_pose = *pose * local_pose(world, mc);
        for &oc in fixed {
            if !clear_of(&m_pose, mc, world.colliders[oc].position(), oc) {
                return false;
            }
        }
    }
    for &b in blockers {
        if b == mover {
            continue;
        }
        let other = &world.bodies[b];
        let gap = (other.translation() - pose.translation).length();
        if gap > reach + body_reach(world, b) + clearance {
            continue;
        }
        for &oc in other.colliders() {
            let o_pose = *other.position() * local_pose(world, oc);
            for &mc in movers.colliders() {
                if !clear_of(&(*pose * local_pose(world, mc)), mc, &o_pose, oc) {
                    return false;
                }
            }
        }
    }
    true
}

/// A collider's pose in its body's frame.
fn local_pose(world: &PhysicsWorld, c: ColliderHandle) -> Pose {
    world.colliders[c]
        .position_wrt_parent()
        .copied()
        .unwrap_or(Pose::IDENTITY)
}

/// Radius around a body's origin that holds all its colliders, metres.
pub(crate) fn body_reach(world: &PhysicsWorld, body: RigidBodyHandle) -> f32 {
    world.bodies[body]
        .colliders()
        .iter()
        .map(|&c| {
            let shape = world.colliders[c].shape();
            let local = local_pose(world, c);
            let aabb = shape.compute_aabb(&local);
            aabb.mins.abs().max(aabb.maxs.abs()).length()
        })
        .fold(0.0, f32::max)
}
