//! Passes: possession moves from one teammate to another after a kick by the
//! first, with no opponent control between. Counted once, when the receiver
//! takes control.

use naosoccer_proto::{Event, RobotId};

use super::Outcome;

#[derive(Debug, Clone, Default)]
pub struct PassRule {
    /// The robot that last controlled or kicked the ball since play restarted.
    holder: Option<RobotId>,
    /// Whether `holder` has kicked the ball since it became the holder.
    kicked: bool,
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
        holder << 1 | u64::from(self.kicked)
    }

    /// A kick that moved the ball. A kicker that had not been seen in control
    /// (the ball reached its foot between two ticks) becomes the holder.
    pub fn kick(&mut self, robot: RobotId) {
        if self.holder != Some(robot) {
            self.holder = Some(robot);
        }
        self.kicked = true;
    }

    /// The tick's controller, after the tick's kicks were reported.
    pub fn control(&mut self, controller: Option<RobotId>, tick: u64, out: &mut Outcome) {
        let Some(to) = controller else {
            return;
        };
        if self.holder == Some(to) {
            return;
        }
        if let Some(from) = self.holder {
            if self.kicked && from.team() == to.team() {
                out.events.push(Event::Pass {
                    tick,
                    from,
                    to,
                    distance: 0.0,
                });
            }
        }
        self.holder = Some(to);
        self.kicked = false;
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
        rule.control(Some(a), 1, &mut out);
        rule.kick(a);
        rule.control(None, 2, &mut out);
        rule.control(Some(b), 5, &mut out);
        rule.control(Some(b), 6, &mut out);
        rule.control(None, 7, &mut out);
        rule.control(Some(b), 8, &mut out);
        assert_eq!(
            out.events,
            vec![Event::Pass {
                tick: 5,
                from: a,
                to: b,
                distance: 0.0,
            }]
        );
    }

    #[test]
    fn no_kick_or_opponent_between_is_no_pass() {
        let (a, b, o) = (r(Team::Blue, 1), r(Team::Blue, 2), r(Team::Red, 0));
        let mut rule = PassRule::new();
        let mut out = Outcome::default();
        // Taken off a teammate's feet without a kick.
        rule.control(Some(a), 1, &mut out);
        rule.control(Some(b), 2, &mut out);
        // Kicked, intercepted, then back to blue.
        rule.kick(b);
        rule.control(Some(o), 3, &mut out);
        rule.control(Some(a), 4, &mut out);
        assert_eq!(passes(&out), 0);
        // A restart between kick and reception.
        rule.kick(a);
        rule.reset();
        rule.control(Some(b), 9, &mut out);
        assert_eq!(passes(&out), 0);
    }
}
