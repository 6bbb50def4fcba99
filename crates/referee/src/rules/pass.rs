//! Passes: possession moves from one teammate to another after a kick by the
//! first, with no opponent control between. Counted once, when the receiver
//! takes control.

use naosoccer_proto::{Event, RobotId, Tick};

use super::outcome::Outcome;

#[derive(Debug, Clone, Default)]
pub struct PassRule {
    /// The robot that last controlled or kicked the ball since play restarted.
    holder: Option<RobotId>,
    /// Whether `holder` has kicked the ball since it became the holder.
    kicked: bool,
    /// Where the ball was when `holder` last kicked it (world frame).
    kicked_at: [f32; 2],
    /// Whether that kick was a `pass` swung toward a receiver. Reported in
    /// the `pass` event only; left out of the fingerprint, as the sim's
    /// hash holds the pass target that made it.
    aimed: bool,
}

/// A pass the rule counted.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PassMade {
    pub from: RobotId,
    pub to: RobotId,
    /// Ball positions at the kick and at the reception, world frame.
    pub start: [f32; 2],
    pub end: [f32; 2],
    /// The kick was a `pass` swung toward a receiver.
    pub aimed: bool,
}

impl PassRule {
    pub fn new() -> PassRule {
        PassRule::default()
    }

    /// Play restarted (kick-off, ball put back in): no pass spans it.
    pub fn reset(&mut self) {
        *self = PassRule::default();
    }

    /// The rule's memory as one number, for the match's state hash.
    pub fn fingerprint(&self) -> u64 {
        let holder = self.holder.map_or(0xff, |r| r.index() as u64);
        let at =
            u64::from(self.kicked_at[0].to_bits()) << 32 | u64::from(self.kicked_at[1].to_bits());
        (holder << 1 | u64::from(self.kicked)) ^ at.rotate_left(9)
    }

    /// A kick that moved the ball, which lay at `ball` (world frame);
    /// `aimed` when it was a `pass` swung toward a receiver. A kicker that
    /// had not been seen in control (the ball reached its foot between two
    /// ticks) becomes the holder.
    pub fn kick(&mut self, robot: RobotId, ball: [f32; 2], aimed: bool) {
        if self.holder != Some(robot) {
            self.holder = Some(robot);
        }
        self.kicked = true;
        self.kicked_at = ball;
        self.aimed = aimed;
    }

    /// The tick's controller, after the tick's kicks were reported; `ball`
    /// is where the ball is now. Returns the pass made, if any.
    pub fn control(
        &mut self,
        controller: Option<RobotId>,
        ball: [f32; 2],
        tick: Tick,
        out: &mut Outcome,
    ) -> Option<PassMade> {
        let to = controller?;
        if self.holder == Some(to) {
            return None;
        }
        let mut made = None;
        if let Some(from) = self.holder {
            if self.kicked && from.team() == to.team() {
                let start = self.kicked_at;
                let distance = (ball[0] - start[0]).hypot(ball[1] - start[1]);
                out.events.push(Event::Pass {
                    tick,
                    from,
                    to,
                    distance,
                    aimed: self.aimed,
                });
                made = Some(PassMade {
                    from,
                    to,
                    start,
                    end: ball,
                    aimed: self.aimed,
                });
            }
        }
        self.holder = Some(to);
        self.kicked = false;
        self.aimed = false;
        made
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use naosoccer_proto::Team;

    fn r(team: Team, p: usize) -> RobotId {
        RobotId::new(team, p).unwrap()
    }

    fn passes(out: &Outcome) -> usize {
        out.events
            .iter()
            .filter(|e| matches!(e, Event::Pass { .. }))
            .count()
    }

    #[test]
    fn kick_then_teammate_control_is_one_pass() {
        let (a, b) = (r(Team::Blue, 1), r(Team::Blue, 2));
        let mut rule = PassRule::new();
        let mut out = Outcome::default();
        let z = [0.0, 0.0];
        rule.control(Some(a), z, Tick::new(1), &mut out);
        rule.kick(a, [1.0, 1.0], true);
        rule.control(None, z, Tick::new(2), &mut out);
        let made = rule.control(Some(b), [4.0, 5.0], Tick::new(5), &mut out);
        assert_eq!(
            made,
            Some(PassMade {
                from: a,
                to: b,
                start: [1.0, 1.0],
                end: [4.0, 5.0],
                aimed: true,
            })
        );
        rule.control(Some(b), z, Tick::new(6), &mut out);
        rule.control(None, z, Tick::new(7), &mut out);
        rule.control(Some(b), z, Tick::new(8), &mut out);
        assert_eq!(
            out.events,
            vec![Event::Pass {
                tick: Tick::new(5),
                from: a,
                to: b,
                distance: 5.0,
                aimed: true,
            }]
        );
    }

    #[test]
    fn a_pass_is_aimed_by_the_last_kick_before_it() {
        let (a, b) = (r(Team::Blue, 1), r(Team::Blue, 2));
        let mut rule = PassRule::new();
        let mut out = Outcome::default();
        let z = [0.0, 0.0];
        // An aimed kick the kicker followed and kicked again as a shot.
        rule.control(Some(a), z, Tick::new(1), &mut out);
        rule.kick(a, z, true);
        rule.control(Some(a), z, Tick::new(2), &mut out);
        rule.kick(a, z, false);
        let made = rule.control(Some(b), z, Tick::new(3), &mut out).unwrap();
        assert!(!made.aimed);
        // A shot, then an aimed kick: aimed.
        rule.kick(b, z, false);
        rule.control(Some(b), z, Tick::new(4), &mut out);
        rule.kick(b, z, true);
        assert!(
            rule.control(Some(a), z, Tick::new(5), &mut out)
                .unwrap()
                .aimed
        );
        // The fingerprint does not hold the aim (the sim's hash does).
        let mut other = rule.clone();
        rule.kick(a, [1.0, 2.0], true);
        other.kick(a, [1.0, 2.0], false);
        assert_eq!(rule.fingerprint(), other.fingerprint());
        let aimed: Vec<bool> = out
            .events
            .iter()
            .filter_map(|e| match e {
                Event::Pass { aimed, .. } => Some(*aimed),
                _ => None,
            })
            .collect();
        assert_eq!(aimed, [false, true]);
    }

    #[test]
    fn no_kick_or_opponent_between_is_no_pass() {
        let (a, b, o) = (r(Team::Blue, 1), r(Team::Blue, 2), r(Team::Red, 0));
        let mut rule = PassRule::new();
        let mut out = Outcome::default();
        let z = [0.0, 0.0];
        // Taken off a teammate's feet without a kick.
        rule.control(Some(a), z, Tick::new(1), &mut out);
        rule.control(Some(b), z, Tick::new(2), &mut out);
        // Kicked, intercepted, then back to blue.
        rule.kick(b, z, false);
        rule.control(Some(o), z, Tick::new(3), &mut out);
        rule.control(Some(a), z, Tick::new(4), &mut out);
        assert_eq!(passes(&out), 0);
        // A restart between kick and reception.
        rule.kick(a, z, true);
        rule.reset();
        rule.control(Some(b), z, Tick::new(9), &mut out);
        assert_eq!(passes(&out), 0);
    }
}
