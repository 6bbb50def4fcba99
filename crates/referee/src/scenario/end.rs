//! When a scenario's play ends, and with what outcome: the file's end
//! conditions, checked after every tick in file order, and the time limit.

use naosoccer_proto::{Event, Team, Tick};

use crate::Match;

/// One end condition of a scenario (`when` in the file).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum EndKind {
    /// The own team scored (own goals by the opponents included).
    GoalFor,
    /// The opponents scored.
    GoalAgainst,
    /// The ball went out over a touch or goal line (not in a goal).
    BallOut,
    /// An opponent controls the ball (the paper's `if_c`).
    PossessionLost,
    /// An own robot controls the ball.
    PossessionWon,
    /// The duration is over, the half ended within it, or the match ended.
    TimeUp,
    /// The ball's centre is inside the rectangle (own team's frame, ends
    /// included).
    Region { x: [f32; 2], y: [f32; 2] },
}

impl EndKind {
    /// Its name in files and reports.
    pub fn name(&self) -> &'static str {
        match self {
            EndKind::GoalFor => "goal_for",
            EndKind::GoalAgainst => "goal_against",
            EndKind::BallOut => "ball_out",
            EndKind::PossessionLost => "possession_lost",
            EndKind::PossessionWon => "possession_won",
            EndKind::TimeUp => "time_up",
            EndKind::Region { .. } => "region",
        }
    }

    /// Every name a file may give `when`.
    pub const NAMES: [&'static str; 7] = [
        "goal_for",
        "goal_against",
        "ball_out",
        "possession_lost",
        "possession_won",
        "time_up",
        "region",
    ];

    /// The condition `when` names; `x` and `y` only for a region. The
    /// error names the offending key (`when`, `x`, `y`) and says why.
    pub(super) fn parse(
        when: &str,
        x: Option<[f32; 2]>,
        y: Option<[f32; 2]>,
    ) -> Result<EndKind, (&'static str, String)> {
        let kind = match when {
            "goal_for" => EndKind::GoalFor,
            "goal_against" => EndKind::GoalAgainst,
            "ball_out" => EndKind::BallOut,
            "possession_lost" => EndKind::PossessionLost,
            "possession_won" => EndKind::PossessionWon,
            "time_up" => EndKind::TimeUp,
            "region" => {
                let (Some(x), Some(y)) = (x, y) else {
                    return Err((
                        if x.is_none() { "x" } else { "y" },
                        "is missing: a region needs x = [low, high] and y = [low, high]".into(),
                    ));
                };
                for (r, key) in [(x, "x"), (y, "y")] {
                    if !(r[0].is_finite() && r[1].is_finite() && r[0] <= r[1]) {
                        return Err((key, format!("is {r:?}: [low, high] with low <= high")));
                    }
                }
                return Ok(EndKind::Region { x, y });
            }
            other => {
                return Err((
                    "when",
                    format!("is \"{other}\": one of {}", EndKind::NAMES.join(", ")),
                ))
            }
        };
        if x.is_some() || y.is_some() {
            return Err((
                if x.is_some() { "x" } else { "y" },
                format!("is only for `when = \"region\"`, not \"{when}\""),
            ));
        }
        Ok(kind)
    }
}

/// How a scenario's play ended.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ending {
    pub kind: EndKind,
    pub success: bool,
    /// Control ticks played from the start, the ending tick included.
    pub ticks: u64,
}

/// Decides when a scenario's play ends (see [`EndKind`]).
#[derive(Debug, Clone)]
pub struct Judge {
    own: Team,
    start: Tick,
    limit: Option<u64>,
    ends: Vec<(EndKind, bool)>,
}

impl Judge {
    /// `limit`: control ticks the play lasts at most.
    pub fn new(own: Team, start: Tick, limit: Option<u64>, ends: Vec<(EndKind, bool)>) -> Judge {
        Judge {
            own,
            start,
            limit,
            ends,
        }
    }

    /// The colour the own team plays.
    pub fn own(&self) -> Team {
        self.own
    }

    /// After a tick (`events` are the tick's): the first end condition,
    /// in file order, that holds; else, once time is up, `time_up` with
    /// the file's outcome for it, a failure if it names none.
    pub fn check(&self, m: &Match, events: &[Event]) -> Option<Ending> {
        let ticks = m.tick().saturating_since(self.start);
        // Half time puts everybody back in the kick-off places: a play with
        // a duration ends there; one without plays on to the match's end.
        let half_time = events.iter().any(|e| matches!(e, Event::HalfTime { .. }));
        let time_up = m.is_finished() || self.limit.is_some_and(|l| ticks >= l || half_time);
        let holds = |kind: &EndKind| match *kind {
            EndKind::GoalFor => goal(events, self.own),
            EndKind::GoalAgainst => goal(events, self.own.other()),
            EndKind::BallOut => events.iter().any(|e| matches!(e, Event::BallOut { .. })),
            EndKind::PossessionLost => m.controller().is_some_and(|c| c.team() != self.own),
            EndKind::PossessionWon => m.controller().is_some_and(|c| c.team() == self.own),
            EndKind::TimeUp => time_up,
            EndKind::Region { x, y } => {
                let [bx, by, _] = m.sim().snapshot().ball.pos;
                let s = self.own.direction();
                let (bx, by) = (s * bx, s * by);
                (x[0]..=x[1]).contains(&bx) && (y[0]..=y[1]).contains(&by)
            }
        };
        if let Some(&(kind, success)) = self.ends.iter().find(|(k, _)| holds(k)) {
            return Some(Ending {
                kind,
                success,
                ticks,
            });
        }
        time_up.then_some(Ending {
            kind: EndKind::TimeUp,
            success: false,
            ticks,
        })
    }
}

fn goal(events: &[Event], team: Team) -> bool {
    events
        .iter()
        .any(|e| matches!(e, Event::Goal { team: t, .. } if *t == team))
}
