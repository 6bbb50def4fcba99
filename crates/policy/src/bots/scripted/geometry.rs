//! Plane geometry of the scripted team: points as `[x, y]` in metres.

use naosoccer_proto::{Action, RobotObs};

/// Where to walk from `from` toward `to` without crossing the circle of
/// radius `r` round `centre`: `to` itself when the straight path stays
/// outside, else a point on the circle at most a radian further round
/// from `from`, on the shorter way.
pub(super) fn around(centre: [f32; 2], from: [f32; 2], to: [f32; 2], r: f32) -> [f32; 2] {
    let seg = sub(to, from);
    let len2 = dot(seg, seg).max(1e-9);
    let t = (dot(sub(centre, from), seg) / len2).clamp(0.0, 1.0);
    if dist(add(from, scale(seg, t)), centre) >= r {
        return to;
    }
    let a_from = sub(from, centre);
    let a_to = sub(to, centre);
    let a0 = a_from[1].atan2(a_from[0]);
    let step = wrap(a_to[1].atan2(a_to[0]) - a0).clamp(-1.0, 1.0);
    let rad = r.max(norm(a_from));
    let a = a0 + step;
    [centre[0] + rad * a.cos(), centre[1] + rad * a.sin()]
}

pub(super) fn turn_towards(err: f32) -> Action {
    if err > 0.0 {
        Action::TurnLeft
    } else {
        Action::TurnRight
    }
}

/// The ball in the robot's frame: (ahead, to the left).
pub(super) fn local(me: &RobotObs, p: [f32; 2]) -> (f32, f32) {
    let d = sub(p, [me.x, me.y]);
    let (s, c) = me.heading.sin_cos();
    (d[0] * c + d[1] * s, -d[0] * s + d[1] * c)
}

pub(super) fn wrap(a: f32) -> f32 {
    use std::f32::consts::{PI, TAU};
    let a = a % TAU;
    if a > PI {
        a - TAU
    } else if a <= -PI {
        a + TAU
    } else {
        a
    }
}

pub(super) fn sub(a: [f32; 2], b: [f32; 2]) -> [f32; 2] {
    [a[0] - b[0], a[1] - b[1]]
}
pub(super) fn add(a: [f32; 2], b: [f32; 2]) -> [f32; 2] {
    [a[0] + b[0], a[1] + b[1]]
}
pub(super) fn scale(a: [f32; 2], k: f32) -> [f32; 2] {
    [a[0] * k, a[1] * k]
}
pub(super) fn dot(a: [f32; 2], b: [f32; 2]) -> f32 {
    a[0] * b[0] + a[1] * b[1]
}
pub(super) fn cross(a: [f32; 2], b: [f32; 2]) -> f32 {
    a[0] * b[1] - a[1] * b[0]
}
pub(super) fn norm(a: [f32; 2]) -> f32 {
    a[0].hypot(a[1])
}
pub(super) fn dist(a: [f32; 2], b: [f32; 2]) -> f32 {
    norm(sub(a, b))
}
