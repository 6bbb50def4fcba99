//! A goal: the whole ball behind a goal line, between the posts, under the
//! crossbar. The team attacking that goal scores; the conceding team kicks off
//! with the ball back on the centre spot.

use naosoccer_proto::{Event, Team, Tick};
use naosoccer_sim::Snapshot;

use super::field::{last_touch, Field};
use super::outcome::{Command, Outcome};

#[derive(Debug, Clone, Copy)]
pub struct GoalRule {
    field: Field,
}

impl GoalRule {
    pub fn new(field: Field) -> GoalRule {
        GoalRule { field }
    }

    /// The team that has scored with the ball where it is now, if any.
    pub fn scored(&self, snap: &Snapshot) -> Option<Team> {
        let f = &self.field;
        let [x, y, z] = snap.ball.pos;
        let r = f.ball_radius;
        let behind = x.abs() > f.half_length + r;
        // The ball's centre between the inner edges of the posts, and its top
        // under the crossbar: a ball on a post or on the bar is not in.
        let in_mouth = y.abs() < f.goal_half_width - r && z + r < f.crossbar;
        if !(behind && in_mouth) {
            return None;
        }
        // Behind +x is red's goal: blue scored.
        Some(if x > 0.0 { Team::Blue } else { Team::Red })
    }

    /// Emits the goal and the kick-off by the conceding team. Returns the
    /// scoring team so the driver can skip the rules a goal makes moot.
    pub fn check(&self, snap: &Snapshot, tick: Tick, out: &mut Outcome) -> Option<Team> {
        let team = self.scored(snap)?;
        // Own goals count for the other team but have no scorer.
        let scorer = last_touch(snap).filter(|r| r.team() == team);
        out.events.push(Event::Goal { tick, team, scorer });
        out.commands.push(Command::KickOff { team: team.other() });
        Some(team)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rules::testing::{field, snapshot};

    fn with_ball(x: f32, y: f32, z: f32) -> Snapshot {
        let mut s = snapshot();
        s.ball.pos = [x, y, z];
        s
    }

    #[test]
    fn whole_ball_behind_the_line_between_posts_under_bar_scores() {
        let rule = GoalRule::new(field());
        assert_eq!(rule.scored(&with_ball(3.2, 0.0, 0.05)), Some(Team::Blue));
        assert_eq!(rule.scored(&with_ball(-3.2, 1.0, 0.05)), Some(Team::Red));
    }

    #[test]
    fn ball_on_the_line_does_not_score() {
        let rule = GoalRule::new(field());
        // Centre past the line but part of the ball still over it.
        assert_eq!(rule.scored(&with_ball(3.03, 0.0, 0.05)), None);
    }

    #[test]
    fn wide_or_over_the_bar_does_not_score() {
        let rule = GoalRule::new(field());
        assert_eq!(rule.scored(&with_ball(3.2, 1.4, 0.05)), None);
        assert_eq!(rule.scored(&with_ball(3.2, -2.0, 0.05)), None);
        assert_eq!(rule.scored(&with_ball(3.2, 0.0, 0.9)), None);
    }

    #[test]
    fn goal_emits_event_and_kickoff_for_the_conceding_team() {
        let rule = GoalRule::new(field());
        let mut out = Outcome::default();
        assert_eq!(
            rule.check(&with_ball(-3.3, 0.0, 0.05), Tick::new(42), &mut out),
            Some(Team::Red)
        );
        assert_eq!(
            out.events,
            vec![Event::Goal {
                tick: Tick::new(42),
                team: Team::Red,
                scorer: None
            }]
        );
        assert_eq!(out.commands, vec![Command::KickOff { team: Team::Blue }]);
    }
}
