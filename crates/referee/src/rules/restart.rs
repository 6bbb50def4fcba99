//! What the touches since the last restart decide: whether a goal counts
//! (the kick-off rule) and how it came about (goals by phase).
//!
//! - **Kick-off rule** (SPL until 2022): after a kick-off, a goal by the
//!   kicking team counts only once a robot other than the kicker (the first
//!   robot to touch the ball) has touched it. Until then such a goal is
//!   disallowed and play restarts with a goal kick for the other team.
//!   `rules.direct_kick_off_goals = true` turns the rule off.
//! - **Goals by phase**: a goal is an own goal when a robot of the conceding
//!   team touched the ball last; from a restart when the scoring team was
//!   awarded the last restart (kick-off or set play), only its robots have
//!   touched the ball since, and the goal comes within `window_ticks` of the
//!   award; otherwise from open play.
//!
//! Touches come from the sim's per-robot record of the last physics step on
//! which each robot touched the ball: the robots whose record moved during
//! a tick touched it in that tick. When two or more robots touch it in one
//! tick the rule does not need their order: both "another robot touched it"
//! and "the other team touched it" follow from the set alone.

use naosoccer_proto::{GoalPhase, RobotId, Team, Tick, ROBOTS};

/// The kick-off in progress, for the kick-off rule.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum KickOffTouch {
    /// No kick-off whose goal could be disallowed.
    Done,
    /// `team` kicked off; nobody has touched the ball yet.
    Awaiting(Team),
    /// `kicker` (of the kicking team) alone has touched it since.
    Kicked(RobotId),
}

/// The last restart, for goals by phase.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct RestartPhase {
    team: Team,
    awarded: Tick,
}

#[derive(Debug, Clone)]
pub struct RestartRule {
    kick_off_rule: bool,
    window_ticks: u64,
    kick_off: KickOffTouch,
    restart: Option<RestartPhase>,
}

impl RestartRule {
    /// `kick_off_rule`: whether direct kick-off goals are disallowed;
    /// `window_ticks`: how long after its award a goal still counts as
    /// from a restart.
    pub fn new(kick_off_rule: bool, window_ticks: u64) -> RestartRule {
        RestartRule {
            kick_off_rule,
            window_ticks,
            kick_off: KickOffTouch::Done,
            restart: None,
        }
    }

    /// A kick-off for `team`, first played at `first_tick`.
    pub fn kick_off(&mut self, team: Team, first_tick: Tick) {
        self.kick_off = KickOffTouch::Awaiting(team);
        self.restart = Some(RestartPhase {
            team,
            awarded: first_tick,
        });
    }

    /// A staged situation: no kick-off or restart in progress.
    pub fn clear(&mut self) {
        self.kick_off = KickOffTouch::Done;
        self.restart = None;
    }

    /// A set play for `team` (kick-in, goal kick, corner kick), first
    /// played at `first_tick`. It ends any kick-off.
    pub fn set_play(&mut self, team: Team, first_tick: Tick) {
        self.kick_off = KickOffTouch::Done;
        self.restart = Some(RestartPhase {
            team,
            awarded: first_tick,
        });
    }

    /// The robots that touched the ball during the tick (`touched[i]` for
    /// robot index `i`).
    pub fn touches(&mut self, touched: &[bool; ROBOTS]) {
        let mut who = (0..ROBOTS)
            .filter(|&i| touched[i])
            .filter_map(RobotId::from_index);
        let Some(first) = who.next() else {
            return;
        };
        let several = who.next().is_some();
        self.kick_off = match self.kick_off {
            KickOffTouch::Done => KickOffTouch::Done,
            _ if several => KickOffTouch::Done,
            KickOffTouch::Awaiting(team) if first.team() == team => KickOffTouch::Kicked(first),
            KickOffTouch::Awaiting(_) => KickOffTouch::Done,
            KickOffTouch::Kicked(kicker) if first == kicker => KickOffTouch::Kicked(kicker),
            KickOffTouch::Kicked(_) => KickOffTouch::Done,
        };
        if let Some(r) = self.restart {
            let other_team_touched = (0..ROBOTS)
                .filter(|&i| touched[i])
                .filter_map(RobotId::from_index)
                .any(|robot| robot.team() != r.team);
            if other_team_touched {
                self.restart = None;
            }
        }
    }

    /// Whether a goal for `team` now is scored straight from its kick-off
    /// (and the rule applies).
    pub fn disallows(&self, team: Team) -> bool {
        // A ball nobody touched since the kick-off was not kicked in from
        // it (only staged situations see one).
        self.kick_off_rule
            && matches!(self.kick_off, KickOffTouch::Kicked(kicker) if kicker.team() == team)
    }

    /// The phase of a goal for `team` at `tick`, the ball last touched by
    /// `last_touch`.
    pub fn phase(&self, team: Team, last_touch: Option<RobotId>, tick: Tick) -> GoalPhase {
        if last_touch.is_some_and(|r| r.team() != team) {
            return GoalPhase::OwnGoal;
        }
        match self.restart {
            Some(r) if r.team == team && tick.saturating_since(r.awarded) <= self.window_ticks => {
                GoalPhase::Restart
            }
            _ => GoalPhase::OpenPlay,
        }
    }

    /// The rule's memory as one number, for the match's state hash.
    pub fn fingerprint(&self) -> u64 {
        let k = match self.kick_off {
            KickOffTouch::Done => u64::MAX,
            KickOffTouch::Awaiting(t) => 100 + t.index() as u64,
            KickOffTouch::Kicked(r) => r.index() as u64,
        };
        let r = self
            .restart
            .map_or(u64::MAX, |r| r.awarded.get() * 2 + r.team.index() as u64);
        k.wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ r
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn robot(team: Team, p: usize) -> RobotId {
        RobotId::new(team, p).unwrap()
    }

    fn touched(robots: &[RobotId]) -> [bool; ROBOTS] {
        let mut t = [false; ROBOTS];
        for r in robots {
            t[r.index()] = true;
        }
        t
    }

    #[test]
    fn a_kick_off_goal_counts_only_after_another_robot_touched_the_ball() {
        let mut rule = RestartRule::new(true, 150);
        rule.kick_off(Team::Blue, Tick::new(1));
        // Nobody kicked yet: nothing to disallow.
        assert!(!rule.disallows(Team::Blue));
        // The kicker touches it, twice: still direct.
        rule.touches(&touched(&[robot(Team::Blue, 1)]));
        rule.touches(&touched(&[robot(Team::Blue, 1)]));
        assert!(rule.disallows(Team::Blue));
        // A teammate touches it: the goal counts.
        rule.touches(&touched(&[robot(Team::Blue, 2)]));
        assert!(!rule.disallows(Team::Blue));

        // An opponent's touch counts too.
        rule.kick_off(Team::Red, Tick::new(100));
        rule.touches(&touched(&[robot(Team::Red, 1)]));
        rule.touches(&touched(&[robot(Team::Blue, 3)]));
        assert!(!rule.disallows(Team::Red));

        // Two robots in one tick: another robot than the kicker touched it.
        rule.kick_off(Team::Red, Tick::new(200));
        rule.touches(&touched(&[robot(Team::Red, 1), robot(Team::Red, 2)]));
        assert!(!rule.disallows(Team::Red));

        // A set play ends the kick-off; so does the rule's switch.
        rule.kick_off(Team::Blue, Tick::new(300));
        rule.touches(&touched(&[robot(Team::Blue, 1)]));
        assert!(rule.disallows(Team::Blue));
        rule.set_play(Team::Blue, Tick::new(310));
        assert!(!rule.disallows(Team::Blue));
        let mut off = RestartRule::new(false, 150);
        off.kick_off(Team::Blue, Tick::new(1));
        off.touches(&touched(&[robot(Team::Blue, 1)]));
        assert!(!off.disallows(Team::Blue));
    }

    #[test]
    fn goals_are_classified_by_the_touches_since_the_restart() {
        let mut rule = RestartRule::new(true, 150);
        let b1 = robot(Team::Blue, 1);
        let r2 = robot(Team::Red, 2);
        rule.set_play(Team::Blue, Tick::new(10));
        rule.touches(&touched(&[b1]));
        rule.touches(&touched(&[robot(Team::Blue, 3)]));
        assert_eq!(
            rule.phase(Team::Blue, Some(b1), Tick::new(160)),
            GoalPhase::Restart
        );
        // Too late for a restart goal.
        assert_eq!(
            rule.phase(Team::Blue, Some(b1), Tick::new(161)),
            GoalPhase::OpenPlay
        );
        // The other team's restart.
        assert_eq!(
            rule.phase(Team::Red, Some(r2), Tick::new(20)),
            GoalPhase::OpenPlay
        );
        // Last touched by the conceding team: an own goal, whatever else.
        assert_eq!(
            rule.phase(Team::Blue, Some(r2), Tick::new(20)),
            GoalPhase::OwnGoal
        );
        // An opponent touched it since: open play.
        rule.touches(&touched(&[r2]));
        rule.touches(&touched(&[b1]));
        assert_eq!(
            rule.phase(Team::Blue, Some(b1), Tick::new(30)),
            GoalPhase::OpenPlay
        );
    }
}
