//! A goal: the whole ball behind a goal line, between the posts, under the
//! crossbar. The team attacking that goal scores; the conceding team kicks off
//! with the ball back on the centre spot. A goal straight from the scoring
//! team's kick-off does not count ([`RestartRule`]): play restarts with a
//! goal kick for the other team.

use naosoccer_proto::{DisallowReason, Event, SetPlayKind, Team, Tick};
use naosoccer_sim::Snapshot;

use super::field::{goal_kick_spot, last_touch, Field};
use super::outcome::{Command, Outcome};
use super::restart::RestartRule;

/// What a ball in a goal came to.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Scored {
    /// A goal for the team.
    Goal(Team),
    /// It would have been the team's goal; it does not count.
    Disallowed(Team),
}

#[derive(Debug, Clone, Copy)]
pub struct GoalRule {
    field: Field,
    goal_area_depth: f32,
    goal_area_half_width: f32,
}

impl GoalRule {
    /// The goal area's size places the goal kick after a disallowed goal.
    pub fn new(field: Field, goal_area_depth: f32, goal_area_width: f32) -> GoalRule {
        GoalRule {
            field,
            goal_area_depth,
            goal_area_half_width: goal_area_width / 2.0,
        }
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

    /// A goal emits the goal, classified by phase, and the kick-off by the
    /// conceding team; a disallowed one its event and the goal kick. The
    /// driver skips the rules a ball in the goal makes moot.
    pub fn check(
        &self,
        snap: &Snapshot,
        tick: Tick,
        restart: &RestartRule,
        out: &mut Outcome,
    ) -> Option<Scored> {
        let team = self.scored(snap)?;
        if restart.disallows(team) {
            out.events.push(Event::GoalDisallowed {
                tick,
                team,
                reason: DisallowReason::DirectKickOff,
            });
            let defenders = team.other();
            let (x, y) = goal_kick_spot(
                &self.field,
                self.goal_area_depth,
                self.goal_area_half_width,
                defenders,
                snap.ball.pos[1],
            );
            out.commands.push(Command::SetPlay {
                kind: SetPlayKind::GoalKick,
                team: defenders,
                x,
                y,
            });
            return Some(Scored::Disallowed(team));
        }
        let last = last_touch(snap);
        let phase = restart.phase(team, last, tick);
        // Own goals count for the other team but have no scorer.
        let scorer = last.filter(|r| r.team() == team);
        out.events.push(Event::Goal {
            tick,
            team,
            scorer,
            phase: Some(phase),
        });
        out.commands.push(Command::KickOff { team: team.other() });
        Some(Scored::Goal(team))
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
        let rule = GoalRule::new(field(), 0.6, 3.4);
        assert_eq!(rule.scored(&with_ball(3.2, 0.0, 0.05)), Some(Team::Blue));
        assert_eq!(rule.scored(&with_ball(-3.2, 1.0, 0.05)), Some(Team::Red));
    }

    #[test]
    fn ball_on_the_line_does_not_score() {
        let rule = GoalRule::new(field(), 0.6, 3.4);
        // Centre past the line but part of the ball still over it.
        assert_eq!(rule.scored(&with_ball(3.03, 0.0, 0.05)), None);
    }

    #[test]
    fn wide_or_over_the_bar_does_not_score() {
        let rule = GoalRule::new(field(), 0.6, 3.4);
        assert_eq!(rule.scored(&with_ball(3.2, 1.4, 0.05)), None);
        assert_eq!(rule.scored(&with_ball(3.2, -2.0, 0.05)), None);
        assert_eq!(rule.scored(&with_ball(3.2, 0.0, 0.9)), None);
    }

    #[test]
    fn goal_emits_event_and_kickoff_for_the_conceding_team() {
        let rule = GoalRule::new(field(), 0.6, 3.4);
        let mut out = Outcome::default();
        let restart = RestartRule::new(true, 150);
        assert_eq!(
            rule.check(
                &with_ball(-3.3, 0.0, 0.05),
                Tick::new(42),
                &restart,
                &mut out
            ),
            Some(Scored::Goal(Team::Red))
        );
        assert_eq!(
            out.events,
            vec![Event::Goal {
                tick: Tick::new(42),
                team: Team::Red,
                scorer: None,
                phase: Some(naosoccer_proto::GoalPhase::OpenPlay),
            }]
        );
        assert_eq!(out.commands, vec![Command::KickOff { team: Team::Blue }]);
    }

    #[test]
    fn a_direct_kick_off_goal_is_disallowed_and_restarts_with_a_goal_kick() {
        let rule = GoalRule::new(field(), 0.6, 3.4);
        let mut restart = RestartRule::new(true, 150);
        restart.kick_off(Team::Blue, Tick::new(1));
        // Blue's striker (robot 1) kicks it; nobody else touches it.
        let mut touched = [false; naosoccer_proto::ROBOTS];
        touched[1] = true;
        restart.touches(&touched);
        let mut out = Outcome::default();
        // Blue's shot into red's goal (+x), on the -y half of the mouth.
        assert_eq!(
            rule.check(
                &with_ball(3.2, -0.4, 0.05),
                Tick::new(20),
                &restart,
                &mut out
            ),
            Some(Scored::Disallowed(Team::Blue))
        );
        assert_eq!(
            out.events,
            vec![Event::GoalDisallowed {
                tick: Tick::new(20),
                team: Team::Blue,
                reason: DisallowReason::DirectKickOff,
            }]
        );
        assert_eq!(
            out.commands,
            vec![Command::SetPlay {
                kind: SetPlayKind::GoalKick,
                team: Team::Red,
                x: 2.4,
                y: -1.7
            }]
        );
    }
}
