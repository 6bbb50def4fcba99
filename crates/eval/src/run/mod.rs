//! The one runner of batches of matches: every match this crate plays (an
//! evaluation's, a league's, a drill's starts) and the CLI's in-process
//! `match` and `bench sim` are played here.
//!
//! A batch is a set of matches ([`Fixture`]s) between two [`Side`]s, the
//! first and the second, each a built-in team or a trained one. The
//! players are built one way: a built-in team gets one policy per robot,
//! `PolicyKind::build(match seed, robot)`, as the server and the robot
//! clients build them; a trained team decides for all its robots in all the
//! batch's matches in one forward pass a tick, its draws and decision state
//! keyed by (match seed, team, player), so that it plays every match as it
//! would alone, in process or over the socket.
//!
//! A match starts from the kick-off, or from a scenario with its own team
//! playing a given colour; it ends with the match clock, or at the
//! scenario's first end condition that holds (its [`Judge`]). The matches
//! are stepped side by side by a [`Stepper`]'s threads; each holds its own
//! match, so the thread count changes no result.
//!
//! [`Batch`] steps many matches; [`play_one`] plays one, watched tick by
//! tick (a recording, a live view, Ctrl-C), and reports its
//! [`MatchOutcome`].

use naosoccer_policy::{LearnedPolicy, PolicyError, PolicyKind};
use naosoccer_proto::{
    Action, Event, MatchStats, Observation, PerTeam, Score, Team, PLAYERS_PER_TEAM, ROBOTS,
};
use naosoccer_referee::{Ending, Match, MatchConfig, Scenario};

use crate::eval::LONG_PASS_METRES;

mod one;
mod slot;
#[cfg(test)]
mod tests;
mod threads;

pub use one::{play_match, play_one, MatchOutcome};
pub use slot::MatchSlot;
pub use threads::Stepper;

/// One side of a batch of matches (of an evaluation, a drill): a built-in
/// team or a trained one.
pub enum Side {
    Builtin(PolicyKind),
    Learned(Box<LearnedPolicy>),
}

impl Side {
    /// `scripted` | `scripted:KEY=VAL,...` | `scripted:FILE.toml` | `random`
    /// | `idle` | `ppo:DIR` | `dqn:DIR` (and the other trained-team specs).
    pub fn parse(spec: &str) -> Result<Side, PolicyError> {
        if !naosoccer_policy::is_builtin_spec(spec) {
            return Ok(Side::Learned(Box::new(LearnedPolicy::load(spec)?)));
        }
        spec.parse::<PolicyKind>()
            .map(Side::Builtin)
            .map_err(|e| PolicyError::Spec {
                spec: spec.to_string(),
                reason: format!("{e}; or ppo:DIR, dqn:DIR"),
            })
    }
}

/// One match of a batch.
#[derive(Debug, Clone, Copy)]
pub struct Fixture<'a> {
    /// Reported back with its result (an evaluation's global match index,
    /// a drill's start).
    pub index: usize,
    pub seed: u64,
    /// The first side plays red.
    pub swapped: bool,
    /// Start from this scenario, its own team playing this colour, instead
    /// of the kick-off; the match ends at the scenario's first end
    /// condition that holds.
    pub scenario: Option<(&'a Scenario, Team)>,
}

impl Fixture<'_> {
    /// A whole match from the kick-off, the first side blue.
    pub fn kick_off(seed: u64) -> Fixture<'static> {
        Fixture {
            index: 0,
            seed,
            swapped: false,
            scenario: None,
        }
    }
}

/// A match of a batch once it ended (or as far as it went).
#[derive(Debug, Clone, PartialEq)]
pub struct Played {
    /// The fixture's.
    pub index: usize,
    pub seed: u64,
    pub swapped: bool,
    /// Control ticks played.
    pub ticks: u64,
    /// Game time played, seconds.
    pub sim_seconds: f64,
    /// By colour.
    pub score: Score,
    pub stats: MatchStats,
    /// `Match::state_hash` when it ended: equal for equal matches on one
    /// build.
    pub state_hash: u64,
    /// Referee events over the match.
    pub events: u64,
    /// By colour: passes of at least [`LONG_PASS_METRES`].
    pub long_passes: PerTeam<u32>,
    /// How a scenario's match ended (`None` without a scenario).
    pub ending: Option<Ending>,
}

/// A match's last tick, as a watcher sees it.
#[derive(Clone, Copy)]
pub struct Ticked<'a> {
    /// The match after the tick.
    pub m: &'a Match,
    /// The actions applied, in robot index order (blue 0..=3, red 0..=3).
    pub actions: &'a [Action; ROBOTS],
    /// The tick's referee events.
    pub events: &'a [Event],
    /// A scenario's end, from the tick it came on.
    pub ending: Option<Ending>,
}

struct Slot {
    game: MatchSlot,
    index: usize,
    swapped: bool,
    event_count: u64,
    long_passes: PerTeam<u32>,
    ending: Option<Ending>,
    over: bool,
}

impl Slot {
    /// The colour the first side (`first`: true) or the second plays.
    fn team_of(&self, first: bool) -> Team {
        if first != self.swapped {
            Team::Blue
        } else {
            Team::Red
        }
    }

    fn played(&self) -> Played {
        let m = self.game.match_ref();
        Played {
            index: self.index,
            seed: m.seed(),
            swapped: self.swapped,
            ticks: m.tick().get(),
            sim_seconds: m.sim_seconds(),
            score: m.score(),
            stats: m.stats(),
            state_hash: m.state_hash(),
            events: self.event_count,
            long_passes: self.long_passes,
            ending: self.ending,
        }
    }
}

/// Matches between two sides, stepped together.
pub struct Batch<'s> {
    first: &'s mut Side,
    second: &'s mut Side,
    slots: Vec<Slot>,
    acts: Vec<usize>,
    /// The threads stepping the matches, from the first tick on (again
    /// when the count asked for changes).
    stepper: Option<Stepper>,
}

impl<'s> Batch<'s> {
    /// The matches of `fixtures`, at their start, with their players.
    pub fn new<'f>(
        cfg: &MatchConfig,
        first: &'s mut Side,
        second: &'s mut Side,
        fixtures: impl IntoIterator<Item = Fixture<'f>>,
    ) -> Result<Batch<'s>, PolicyError> {
        let mut slots = Vec::new();
        for f in fixtures {
            let mut game = MatchSlot::new(cfg, f.seed, f.scenario)?;
            game.build_policies(|r| {
                let side = if (r.team() == Team::Blue) != f.swapped {
                    &*first
                } else {
                    &*second
                };
                match side {
                    Side::Builtin(k) => Some(*k),
                    Side::Learned(_) => None,
                }
            });
            slots.push(Slot {
                game,
                index: f.index,
                swapped: f.swapped,
                event_count: 0,
                long_passes: PerTeam::default(),
                ending: None,
                over: false,
            });
        }
        Ok(Batch {
            first,
            second,
            slots,
            acts: Vec::new(),
            stepper: None,
        })
    }

    /// Whether every match has ended.
    pub fn is_over(&self) -> bool {
        self.slots.iter().all(|s| s.over)
    }

    /// Plays every match to its end, on up to `threads` threads, asking
    /// `stop` before every tick: once it says yes, play stops there and
    /// the answer is false (Ctrl-C).
    pub fn play(&mut self, threads: usize, stop: &dyn Fn() -> bool) -> bool {
        while !self.is_over() {
            if stop() {
                return false;
            }
            self.step(threads);
        }
        true
    }

    /// One control tick of every match that has not ended: each trained
    /// side decides for its robots in all of them at once, then the
    /// matches step, on up to `threads` threads.
    pub fn step(&mut self, threads: usize) {
        let Batch {
            first,
            second,
            slots,
            acts,
            stepper,
        } = self;
        for (is_first, side) in [(true, &mut **first), (false, &mut **second)] {
            let Side::Learned(policy) = side else {
                continue;
            };
            let live: Vec<usize> = (0..slots.len()).filter(|&i| !slots[i].over).collect();
            acts.resize(live.len() * PLAYERS_PER_TEAM, 0usize);
            // Each match's team as one policy playing that match would see
            // it: draws keyed by (match seed, team, player, tick), and the
            // decision-level MDP's per-robot holds kept by the policy.
            let teams: Vec<(u64, &[Observation])> = live
                .iter()
                .map(|&i| {
                    let base = slots[i].team_of(is_first).index() * PLAYERS_PER_TEAM;
                    let g = &slots[i].game;
                    (
                        g.match_ref().seed(),
                        &g.observations()[base..base + PLAYERS_PER_TEAM],
                    )
                })
                .collect();
            policy.act_matches(&teams, acts);
            for (j, &i) in live.iter().enumerate() {
                let base = slots[i].team_of(is_first).index() * PLAYERS_PER_TEAM;
                for p in 0..PLAYERS_PER_TEAM {
                    let a = policy.action(
                        acts[j * PLAYERS_PER_TEAM + p],
                        &slots[i].game.observations()[base + p],
                    );
                    slots[i].game.actions_mut()[base + p] = a;
                }
            }
        }
        let threads = threads.clamp(1, slots.len().max(1));
        if stepper.as_ref().is_none_or(|s| s.threads() != threads) {
            *stepper = Some(Stepper::new(threads).expect("cannot start the stepping threads"));
        }
        if let Some(stepper) = stepper {
            stepper.for_each(slots, step_slot);
        }
    }

    /// The number of matches.
    pub fn len(&self) -> usize {
        self.slots.len()
    }

    /// Whether the batch holds no match.
    pub fn is_empty(&self) -> bool {
        self.slots.is_empty()
    }

    /// Match `i` (in fixture order) after its last tick.
    pub fn ticked(&self, i: usize) -> Ticked<'_> {
        let s = &self.slots[i];
        Ticked {
            m: s.game.match_ref(),
            actions: s.game.actions(),
            events: s.game.events(),
            ending: s.ending,
        }
    }

    /// Match `i` (in fixture order) as far as it went.
    pub fn played(&self, i: usize) -> Played {
        self.slots[i].played()
    }

    /// Every match as far as it went, in fixture order.
    pub fn results(&self) -> Vec<Played> {
        self.slots.iter().map(Slot::played).collect()
    }
}

/// One tick of a match that has not ended: the built-in robots decide, the
/// match steps, and its end (the clock, or a scenario's end condition) is
/// checked.
fn step_slot(slot: &mut Slot) {
    if slot.over {
        return;
    }
    let ending = slot.game.step();
    slot.event_count += slot.game.events().len() as u64;
    for e in slot.game.events() {
        if let Event::Pass { from, distance, .. } = *e {
            if distance >= LONG_PASS_METRES {
                *slot.long_passes.get_mut(from.team()) += 1;
            }
        }
    }
    if slot.game.is_judged() {
        slot.ending = ending;
        slot.over = ending.is_some();
    } else {
        slot.over = slot.game.match_ref().is_finished();
    }
}
