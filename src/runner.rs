//! The in-process match runner: one [`Match`], one policy instance per robot
//! (built as the server builds them, `PolicyKind::build(seed, robot)`), the
//! whole match in one loop. The CLI's `match` and `bench sim` and the
//! end-to-end tests use it, so what they report is what a server match with
//! the same built-in policies would report.

use std::time::Instant;

use naosoccer_policy::{Policy, PolicyKind};
use naosoccer_proto::{Action, Event, MatchStats, Observation, RobotId, ROBOTS};
use naosoccer_referee::{blank_observation, Match, MatchConfig, MatchError};

/// Goals of each team (the protocol's `score`, one shape everywhere).
pub use naosoccer_proto::Score;

/// What a finished match reports.
#[derive(Debug, Clone, PartialEq)]
pub struct MatchOutcome {
    pub seed: u64,
    /// Control ticks played.
    pub ticks: u64,
    /// Game time played, seconds.
    pub sim_seconds: f64,
    /// Wall-clock time the match took, seconds (the only wall-clock figure;
    /// nothing in the match depends on it).
    pub wall_seconds: f64,
    pub score: Score,
    pub stats: MatchStats,
    /// `Match::state_hash` at the end: equal for equal matches on one build.
    pub state_hash: u64,
    /// Referee events over the match.
    pub events: u64,
}

/// One policy per robot, in robot index order (blue 0..=3, red 0..=3).
pub fn build_policies(seed: u64, blue: &PolicyKind, red: &PolicyKind) -> Vec<Box<dyn Policy>> {
    RobotId::all()
        .map(|robot| match robot.team() {
            naosoccer_proto::Team::Blue => blue.build(seed, robot),
            naosoccer_proto::Team::Red => red.build(seed, robot),
        })
        .collect()
}

/// Plays a whole match of `cfg` with `seed`, `blue` against `red`.
/// `progress` is called after every control tick.
pub fn play_match(
    cfg: &MatchConfig,
    seed: u64,
    blue: &PolicyKind,
    red: &PolicyKind,
    progress: impl FnMut(&Match),
) -> Result<MatchOutcome, MatchError> {
    let m = Match::new(cfg, seed)?;
    let policies = build_policies(seed, blue, red);
    Ok(run_to_end(m, policies, progress))
}

/// Plays `m` to its end with one policy per robot (robot index order).
pub fn run_to_end(
    m: Match,
    policies: Vec<Box<dyn Policy>>,
    mut progress: impl FnMut(&Match),
) -> MatchOutcome {
    run_to_end_with(m, policies, |m, _, _| progress(m))
}

/// Plays a whole match like [`play_match`], calling `on_tick` after every
/// control tick with the match, the actions applied and that tick's events
/// (what a recorder needs).
pub fn play_match_with(
    cfg: &MatchConfig,
    seed: u64,
    blue: &PolicyKind,
    red: &PolicyKind,
    on_tick: impl FnMut(&Match, &[Action; ROBOTS], &[Event]),
) -> Result<MatchOutcome, MatchError> {
    let m = Match::new(cfg, seed)?;
    let policies = build_policies(seed, blue, red);
    Ok(run_to_end_with(m, policies, on_tick))
}

/// [`run_to_end`] with the actions and events of every tick.
pub fn run_to_end_with(
    m: Match,
    policies: Vec<Box<dyn Policy>>,
    mut on_tick: impl FnMut(&Match, &[Action; ROBOTS], &[Event]),
) -> MatchOutcome {
    run_until(m, policies, |m, actions, events| {
        on_tick(m, actions, events);
        std::ops::ControlFlow::Continue(())
    })
}

/// [`run_to_end_with`], stopping early after a tick whose `on_tick` says
/// `Break` (Ctrl-C): the outcome is then the match as far as it went
/// (`ticks` below the match's length).
pub fn run_until(
    mut m: Match,
    mut policies: Vec<Box<dyn Policy>>,
    mut on_tick: impl FnMut(&Match, &[Action; ROBOTS], &[Event]) -> std::ops::ControlFlow<()>,
) -> MatchOutcome {
    assert_eq!(policies.len(), ROBOTS, "one policy per robot");
    let start = Instant::now();
    let mut obs: [Observation; ROBOTS] = std::array::from_fn(|_| blank_observation());
    let mut actions = [Action::Stay; ROBOTS];
    let mut events = 0u64;
    let mut tick_events: Vec<Event> = Vec::with_capacity(16);
    while !m.is_finished() {
        for (robot, (o, (policy, action))) in RobotId::all().zip(
            obs.iter_mut()
                .zip(policies.iter_mut().zip(actions.iter_mut())),
        ) {
            m.observe_into(robot.team(), robot.player(), o);
            *action = policy.act(o);
        }
        // `step` lends its events out of the match; a copy into a reused
        // buffer lets `on_tick` see the match and the events together.
        tick_events.clear();
        tick_events.extend_from_slice(m.step(&actions));
        events += tick_events.len() as u64;
        if on_tick(&m, &actions, &tick_events).is_break() {
            break;
        }
    }
    let wall_seconds = start.elapsed().as_secs_f64();
    MatchOutcome {
        seed: m.seed(),
        ticks: m.tick().get(),
        sim_seconds: m.sim_seconds(),
        wall_seconds,
        score: m.score(),
        stats: m.stats(),
        state_hash: m.state_hash(),
        events,
    }
}

impl MatchOutcome {
    /// The `naosoccer match --json` object. `state_hash` is a string of 16
    /// lower-case hex digits: JSON numbers lose precision above 2^53 in many
    /// readers, a string does not.
    pub fn to_json(&self) -> serde_json::Value {
        let team = |t: &naosoccer_proto::TeamStats| {
            serde_json::json!({
                "goals": t.goals,
                "control_rate": t.control_rate,
                "passes": t.passes,
                "shots": t.shots,
                "falls": t.falls,
                "out_of_bounds": t.out_of_bounds,
            })
        };
        serde_json::json!({
            "seed": self.seed,
            "ticks": self.ticks,
            "sim_seconds": self.sim_seconds,
            "wall_seconds": self.wall_seconds,
            "score": { "blue": self.score.blue, "red": self.score.red },
            "stats": { "blue": team(&self.stats.blue), "red": team(&self.stats.red) },
            "state_hash": format!("{:016x}", self.state_hash),
        })
    }
}
