//! The pitch as the rules see it, and the small geometry every rule shares.

use naosoccer_proto::{RobotId, Team};
use naosoccer_sim::{SimConfig, Snapshot};

/// The pitch as the rules see it, in world coordinates (centre spot at the
/// origin, blue's own goal at -x).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Field {
    /// Half the length between the goal lines (metres).
    pub half_length: f32,
    /// Half the width between the touch lines.
    pub half_width: f32,
    /// Half the goal mouth, inner edge of a post to the centre.
    pub goal_half_width: f32,
    /// Height of the crossbar's underside.
    pub crossbar: f32,
    pub ball_radius: f32,
}

impl Field {
    /// The pitch as the sim builds it.
    pub fn from_sim(cfg: &SimConfig) -> Field {
        Field {
            half_length: cfg.field_length / 2.0,
            half_width: cfg.field_width / 2.0,
            goal_half_width: cfg.goal_width / 2.0,
            crossbar: cfg.goal_height,
            ball_radius: cfg.ball_radius,
        }
    }

    /// Whether a point is on the pitch (lines included).
    pub fn contains(&self, x: f32, y: f32, margin: f32) -> bool {
        x.abs() <= self.half_length + margin && y.abs() <= self.half_width + margin
    }
}

/// A goal kick's spot, world frame: the front corner of `defenders`' goal
/// area on the side of `y` (the side where the ball left; +y for 0).
pub fn goal_kick_spot(
    field: &Field,
    goal_area_depth: f32,
    goal_area_half_width: f32,
    defenders: Team,
    y: f32,
) -> (f32, f32) {
    // Blue defends -x.
    let side_x = -defenders.direction();
    let side_y = if y < 0.0 { -1.0 } else { 1.0 };
    (
        side_x * (field.half_length - goal_area_depth),
        side_y * goal_area_half_width,
    )
}

/// The distance from point `p` to the segment `a`-`b` (a point when the
/// two ends meet).
pub fn segment_distance(a: [f32; 2], b: [f32; 2], p: [f32; 2]) -> f32 {
    let (ux, uy) = (b[0] - a[0], b[1] - a[1]);
    let (vx, vy) = (p[0] - a[0], p[1] - a[1]);
    let len2 = ux * ux + uy * uy;
    let t = if len2 < 1e-12 {
        0.0
    } else {
        ((ux * vx + uy * vy) / len2).clamp(0.0, 1.0)
    };
    (vx - t * ux).hypot(vy - t * uy)
}

/// Angle wrapped to (-pi, pi].
pub fn wrap_angle(a: f32) -> f32 {
    use std::f32::consts::{PI, TAU};
    let mut a = a % TAU;
    if a > PI {
        a -= TAU;
    } else if a <= -PI {
        a += TAU;
    }
    a
}

/// The robot that touched the ball last, by the sim's contact record.
pub fn last_touch(snap: &Snapshot) -> Option<RobotId> {
    let mut best: Option<(u64, usize)> = None;
    for (i, r) in snap.robots.iter().enumerate() {
        if let Some(step) = r.last_ball_touch_step {
            // Later touch wins; on the same step the lower index, for a fixed order.
            if best.is_none_or(|(s, _)| step > s) {
                best = Some((step, i));
            }
        }
    }
    best.and_then(|(_, i)| RobotId::from_index(i))
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f32::consts::PI;

    #[test]
    fn wrap_angle_lands_in_half_open_interval() {
        assert!((wrap_angle(PI) - PI).abs() < 1e-6);
        assert!((wrap_angle(-PI) - PI).abs() < 1e-6);
        assert!((wrap_angle(3.0 * PI / 2.0) + PI / 2.0).abs() < 1e-5);
        assert!((wrap_angle(-5.0 * PI / 2.0) + PI / 2.0).abs() < 1e-5);
        assert_eq!(wrap_angle(0.25), 0.25);
    }
}
