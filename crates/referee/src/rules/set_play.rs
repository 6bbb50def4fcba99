//! Set plays (SPL): after a kick-off, kick-in, goal kick or corner kick is
//! awarded, the team that does not take it keeps `distance` from the ball
//! until the ball is played (it has moved from its spot) or `timeout_ticks`
//! have passed. The driver ([`crate::Match`]) enforces it: robots of that
//! team inside the circle at the end of any tick are moved out to its edge
//! ([`SetPlayRule::push_out`]), their steps toward the ball are refused
//! ([`SetPlayRule::blocks_forward`]; they may turn, stand or walk away) and
//! so are their kicks.
//!
//! Tie-breaks, written down: the ball counts as played once its centre is
//! more than [`SetPlayRule::PLAYED`] from its spot (a kick that moves it, a
//! touch that nudges it, or a collision); a set play awarded while another
//! lasts replaces it.

use naosoccer_proto::{Event, RobotId, SetPlayKind, Team, Tick};
use naosoccer_sim::Snapshot;

use super::outcome::Outcome;

/// The set play in progress.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ActiveSetPlay {
    pub kind: SetPlayKind,
    /// The team that takes it.
    pub team: Team,
    /// Where the ball was put, world frame.
    pub spot: (f32, f32),
    /// The first tick at which the other team may approach anyway.
    pub until: Tick,
}

#[derive(Debug, Clone)]
pub struct SetPlayRule {
    distance: f32,
    timeout_ticks: u64,
    active: Option<ActiveSetPlay>,
}

impl SetPlayRule {
    /// The ball is played once it is this far from its spot (metres).
    pub const PLAYED: f32 = 0.05;

    pub fn new(distance: f32, timeout_ticks: u64) -> SetPlayRule {
        SetPlayRule {
            distance,
            timeout_ticks,
            active: None,
        }
    }

    /// The keep-out radius (metres).
    pub fn distance(&self) -> f32 {
        self.distance
    }

    /// A set play starts with the ball at `spot`; `first_tick` is the first
    /// tick played under it.
    pub fn award(&mut self, kind: SetPlayKind, team: Team, spot: (f32, f32), first_tick: Tick) {
        self.active = Some(ActiveSetPlay {
            kind,
            team,
            spot,
            until: first_tick + self.timeout_ticks,
        });
    }

    pub fn active(&self) -> Option<&ActiveSetPlay> {
        self.active.as_ref()
    }

    /// Control ticks left before the timeout, seen at the start of `tick`.
    pub fn ticks_left(&self, tick: Tick) -> u32 {
        self.active.map_or(0, |a| {
            a.until.saturating_since(tick).min(u64::from(u32::MAX)) as u32
        })
    }

    /// Ends the set play when the ball has been played or time is up.
    /// Returns whether it ended this tick.
    pub fn check(&mut self, snap: &Snapshot, tick: Tick) -> bool {
        let Some(a) = self.active else {
            return false;
        };
        let [x, y, _] = snap.ball.pos;
        let moved = (x - a.spot.0).hypot(y - a.spot.1) > Self::PLAYED;
        if moved || tick.next() >= a.until {
            self.active = None;
            return true;
        }
        false
    }

    /// Forgets any set play (a goal, the end of a half).
    pub fn clear(&mut self) {
        self.active = None;
    }

    /// Whether `robot`, standing at (x, y) facing `heading`, must not step
    /// forward now: it belongs to the team that does not take the set play,
    /// is inside the keep-out circle (plus `margin`, the distance a step
    /// covers) and faces toward the ball.
    pub fn blocks_forward(
        &self,
        robot: RobotId,
        x: f32,
        y: f32,
        heading: f32,
        margin: f32,
    ) -> bool {
        let Some(a) = self.active else {
            return false;
        };
        if robot.team() == a.team {
            return false;
        }
        let (dx, dy) = (a.spot.0 - x, a.spot.1 - y);
        let d = dx.hypot(dy);
        d < self.distance + margin && dx * heading.cos() + dy * heading.sin() > 0.0
    }

    /// Where a robot of the other team at (x, y) inside the circle must
    /// go: straight out from the ball to the circle's edge (plus 2 cm).
    /// `None` when it is outside already. (The driver then takes the free
    /// spot outside the circle nearest this point, on the pitch.)
    pub fn push_out(&self, team: Team, x: f32, y: f32) -> Option<(f32, f32)> {
        let a = self.active?;
        if team == a.team {
            return None;
        }
        let (dx, dy) = (x - a.spot.0, y - a.spot.1);
        let d = dx.hypot(dy);
        if d >= self.distance {
            return None;
        }
        // A robot right on the spot goes back toward its own goal.
        let (ux, uy) = if d > 1e-4 {
            (dx / d, dy / d)
        } else {
            (-team.direction(), 0.0)
        };
        let r = self.distance + 0.02;
        Some((a.spot.0 + ux * r, a.spot.1 + uy * r))
    }

    /// The rule's memory as one number, for the match's state hash.
    pub fn fingerprint(&self) -> u64 {
        match self.active {
            None => u64::MAX,
            Some(a) => {
                let mut h = a.until.get();
                h = h.wrapping_mul(31) ^ a.kind.index() as u64;
                h = h.wrapping_mul(31) ^ a.team.index() as u64;
                h = h.wrapping_mul(31) ^ u64::from(a.spot.0.to_bits());
                h.wrapping_mul(31) ^ u64::from(a.spot.1.to_bits())
            }
        }
    }

    /// The event of an award (kick-offs have their own).
    pub fn event(tick: Tick, kind: SetPlayKind, team: Team, spot: (f32, f32), out: &mut Outcome) {
        out.events.push(Event::SetPlay {
            tick,
            play: kind,
            team,
            x: spot.0,
            y: spot.1,
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rules::testing::snapshot;

    fn red(p: usize) -> RobotId {
        RobotId::new(Team::Red, p).unwrap()
    }

    #[test]
    fn ends_when_the_ball_moves_or_time_is_up() {
        let mut rule = SetPlayRule::new(0.6, 10);
        let mut s = snapshot();
        s.ball.pos = [1.0, 2.2, 0.05];
        rule.award(SetPlayKind::KickIn, Team::Blue, (1.0, 2.2), Tick::new(101));
        assert_eq!(rule.ticks_left(Tick::new(101)), 10);
        assert!(!rule.check(&s, Tick::new(101)));
        s.ball.pos = [1.03, 2.2, 0.05];
        assert!(
            !rule.check(&s, Tick::new(102)),
            "a nudge under 5 cm is not play"
        );
        s.ball.pos = [1.1, 2.2, 0.05];
        assert!(rule.check(&s, Tick::new(103)));
        assert!(rule.active().is_none());

        rule.award(SetPlayKind::GoalKick, Team::Red, (2.4, 1.7), Tick::new(201));
        s.ball.pos = [2.4, 1.7, 0.05];
        for t in 201..210 {
            assert!(!rule.check(&s, Tick::new(t)), "tick {t}");
        }
        assert!(rule.check(&s, Tick::new(210)));
    }

    #[test]
    fn only_the_other_team_is_kept_out_and_only_toward_the_ball() {
        let mut rule = SetPlayRule::new(0.6, 10);
        rule.award(SetPlayKind::CornerKick, Team::Blue, (2.95, 2.2), Tick::ZERO);
        let blue = RobotId::new(Team::Blue, 1).unwrap();
        // Red at 0.5 m facing the ball: blocked; facing away: free.
        assert!(rule.blocks_forward(red(1), 2.45, 2.2, 0.0, 0.05));
        assert!(!rule.blocks_forward(red(1), 2.45, 2.2, std::f32::consts::PI, 0.05));
        // Blue takes it: never blocked. Red far away: free.
        assert!(!rule.blocks_forward(blue, 2.45, 2.2, 0.0, 0.05));
        assert!(!rule.blocks_forward(red(2), 1.0, 2.2, 0.0, 0.05));
    }

    #[test]
    fn push_out_goes_straight_out_to_the_edge() {
        let mut rule = SetPlayRule::new(0.6, 10);
        rule.award(SetPlayKind::KickIn, Team::Red, (0.0, -2.2), Tick::ZERO);
        let (x, y) = rule.push_out(Team::Blue, 0.0, -1.9).unwrap();
        assert!(
            (x - 0.0).abs() < 1e-6 && (y - (-2.2 + 0.62)).abs() < 1e-5,
            "{x} {y}"
        );
        assert_eq!(rule.push_out(Team::Red, 0.0, -1.9), None);
        assert_eq!(rule.push_out(Team::Blue, 0.0, -1.0), None);
        // On the spot itself: back toward blue's own goal (-x).
        let (x, _) = rule.push_out(Team::Blue, 0.0, -2.2).unwrap();
        assert!(x < -0.6);
    }
}
