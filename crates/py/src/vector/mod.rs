//! Many matches stepped together, one control tick a step: the vector env's
//! engine, with no Python in it (the bindings in `lib.rs` only move arrays).
//!
//! Each match's controlled robots take their actions from the caller as
//! action indices; the other team is any policy `naosoccer eval` plays
//! (built-in robots built as the runner builds them, `PolicyKind::build(seed,
//! robot)`, or a trained team deciding for all matches in one forward pass,
//! as evaluation does). So a match stepped here with the same seed and the
//! same actions is the match `naosoccer match` plays, state hash and all.
//!
//! With a scenario (docs/SCENARIOS.md) every match starts from it, drawn
//! from the match's seed, the controlled team (blue with both) as its own
//! team, and ends when the scenario's play does: the match `naosoccer match
//! --scenario FILE --own TEAM` plays. With several, every match start (each
//! reset's and each restart) first chooses one of them from its seed
//! (`pick`), on a stream of its own: the chosen scenario's start is the
//! one it draws alone, and a list of one plays as that scenario alone.
//!
//! A finished match is reported once ([`Finished`]) and replaced at once by
//! the slot's next match: slot `i`'s `e`-th match (counting from the last
//! [`VecMatches::reset`] with seed `s`) has seed `s + i + e * n` for `n`
//! slots, so a slot's first match after `reset(s)` is `naosoccer match
//! --seed s+i`. Without [`EnvSpec::restart`] (the PettingZoo env: one
//! match, an episode that ends) a finished match stays as it ended, to be
//! looked at and drawn, and stepping refuses until the next reset.
//!
//! The slots are stepped by the threads every batch of matches is stepped
//! by (a [`Stepper`], as in evaluations and training), started at the
//! first reset and stopped when the env is dropped: every slot is stepped
//! on its own, so the matches come out the same whatever the number of
//! threads. A panic while stepping a slot is caught there and reported as
//! [`VecEnvError::Panicked`].

use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::Arc;

use naosoccer_eval::eval::Side;
use naosoccer_policy::actions::{to_action, SupportSpot};
use naosoccer_policy::PolicyKind;
use naosoccer_policy::{DecisionConfig, NetAction, ObsScale, PolicyError};
use naosoccer_proto::{MatchStats, Observation, RobotId, Score, Team, PLAYERS_PER_TEAM, ROBOTS};
use naosoccer_referee::{Match, MatchConfig, MatchError, Scenario};

use naosoccer_eval::run::Stepper;

mod setup;
mod slot;

use setup::*;
use slot::*;

/// Why an env cannot be built or stepped.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum VecEnvError {
    #[error(transparent)]
    Policy(#[from] PolicyError),
    #[error(transparent)]
    Match(#[from] MatchError),
    #[error("{0}")]
    Config(String),
    #[error("expected {expected} actions (matches x robots), got {got}")]
    ActionCount { expected: usize, got: usize },
    #[error("action {value} of robot {robot} is not one of the {actions} actions (0..{actions})")]
    Action {
        robot: usize,
        value: i64,
        actions: usize,
    },
    #[error("the match of slot {slot} has ended: reset before stepping again")]
    Ended { slot: usize },
    #[error("cannot start a stepping thread: {0}")]
    Thread(#[source] std::io::Error),
    /// A match panicked while stepping (a bug): the matches are left as
    /// they were, and stepping is refused until the next reset.
    #[error("a match panicked while stepping: {0}; reset before stepping again")]
    Panicked(String),
}

/// Which robots the caller drives.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Controlled {
    /// One team's four; the other team is the opponent policy.
    Team(Team),
    /// All eight (self-play): blue's four, then red's, each seen from its
    /// own team's frame.
    Both,
}

impl Controlled {
    pub fn parse(s: &str) -> Result<Controlled, VecEnvError> {
        match s {
            "blue" => Ok(Controlled::Team(Team::Blue)),
            "red" => Ok(Controlled::Team(Team::Red)),
            "both" => Ok(Controlled::Both),
            other => Err(VecEnvError::Config(format!(
                "team {other:?}: expected \"blue\", \"red\" or \"both\""
            ))),
        }
    }

    /// The robots driven, in row order.
    pub fn robots(self) -> Vec<RobotId> {
        RobotId::all().filter(|r| self.drives(*r)).collect()
    }

    fn drives(self, r: RobotId) -> bool {
        match self {
            Controlled::Team(t) => r.team() == t,
            Controlled::Both => true,
        }
    }
}

/// How a vector env is set up.
pub struct EnvSpec {
    pub matches: usize,
    pub controlled: Controlled,
    /// The other team's policy spec (ignored with [`Controlled::Both`]);
    /// `None`: the scenarios' `opponent` ([`VecMatches::opponent`]), and
    /// `scripted` without scenarios.
    pub opponent: Option<String>,
    pub config: MatchConfig,
    /// Observation layout version (1, 2 or 3).
    pub obs_version: u32,
    /// The action set and masks; `None`: the paper's five, none masked.
    pub decision: Option<DecisionConfig>,
    /// Threads stepping the matches, the caller's included (at least 1;
    /// no more than the matches are used).
    pub threads: usize,
    /// The scenarios matches start from, each checked against `config`:
    /// every match start draws one from the match's seed (`pick`). One:
    /// every match starts from it; none: from the kick-off.
    pub scenarios: Vec<Scenario>,
    /// The scenarios' chances, in proportion (finite, at least 0, not all
    /// 0; one a scenario); `None`: equal.
    pub scenario_weights: Option<Vec<f64>>,
    /// Whether a finished match is replaced by the slot's next one in the
    /// same step (the vector env) or stays finished until the next reset.
    pub restart: bool,
}

/// How a scenario's play ended: the scenario's name, its end condition's
/// name, whether that is a success, and the control ticks played from the
/// start.
#[derive(Debug, Clone, PartialEq)]
pub struct ScenarioEnding {
    pub name: String,
    pub ending: &'static str,
    pub success: bool,
    pub ticks: u64,
}

/// A match that ended during a step: what it was and how it ended.
#[derive(Debug, Clone)]
pub struct Finished {
    /// The slot it was played in.
    pub slot: usize,
    pub seed: u64,
    pub ticks: u64,
    pub score: Score,
    pub stats: MatchStats,
    pub state_hash: u64,
    /// The controlled robots' last observations (rows of the layout).
    pub obs: Vec<f32>,
    /// With a scenario: how its play ended.
    pub scenario: Option<ScenarioEnding>,
}

/// What one step writes, for all slots; rows are slot-major.
#[derive(Debug, Default)]
pub struct StepOut {
    pub obs: Vec<f32>,
    pub rewards: Vec<f32>,
    pub terminated: Vec<bool>,
    pub masks: Vec<bool>,
    pub finished: Vec<Finished>,
}

/// What `opponent` reports when every match plays its own scenario's
/// `opponent` (the scenarios name different built-in policies).
pub const PER_SCENARIO: &str = "per scenario";

/// N matches stepped together.
pub struct VecMatches {
    setup: Arc<Setup>,
    /// The opponent as parsed; a trained team decides here, on the caller's
    /// thread, for all slots at once (with [`Controlled::Both`] or
    /// opponents per scenario, an unused idle one).
    opponent: Side,
    /// The opponents' spec as resolved ([`VecMatches::opponent`]).
    opponent_spec: Option<String>,
    threads: usize,
    /// The slots, from the first reset on.
    slots: Vec<Slot>,
    /// The threads that step them, from the first reset on.
    stepper: Option<Stepper>,
    /// A panic's message while stepping, until the next reset.
    panicked: Option<String>,
    /// Action indices per row, kept to hand a trained opponent its share.
    opp_actions: Vec<usize>,
}

impl VecMatches {
    /// The env, its matches not started until [`VecMatches::reset`].
    pub fn new(spec: EnvSpec) -> Result<VecMatches, VecEnvError> {
        if spec.matches == 0 {
            return Err(VecEnvError::Config("num_matches must be at least 1".into()));
        }
        spec.config
            .validate()
            .map_err(|e| VecEnvError::Match(e.into()))?;
        let mut scale = ObsScale::from_config(&spec.config);
        if naosoccer_policy::obs::layout_dim(spec.obs_version).is_none() {
            return Err(VecEnvError::Config(format!(
                "obs_version {}: this build encodes 1 to {}",
                spec.obs_version,
                naosoccer_policy::OBS_VERSION_LATEST
            )));
        }
        scale.version = spec.obs_version;
        let cumulative = cumulative_weights(spec.scenarios.len(), spec.scenario_weights)?;
        let many = spec.scenarios.len() > 1;
        for (i, s) in spec.scenarios.iter().enumerate() {
            if let Err(e) = s.check(&spec.config) {
                return Err(match many {
                    true => VecEnvError::Config(format!("scenario[{i}] ({}): {e}", s.name)),
                    false => MatchError::from(e).into(),
                });
            }
        }
        // The trained team, if any, that decides for all slots; the spec
        // reported; the built-in policy of every match, else of each
        // scenario's.
        let n = spec.scenarios.len();
        let (opponent, opponent_spec, builtin, kinds) = match spec.controlled {
            Controlled::Both => (Side::Builtin(PolicyKind::Idle), None, None, vec![None; n]),
            Controlled::Team(_) => match resolve_opponent(spec.opponent, &spec.scenarios)? {
                Some(o) => {
                    let side = Side::parse(&o)?;
                    let builtin = match &side {
                        Side::Builtin(k) => Some(*k),
                        Side::Learned(_) => None,
                    };
                    (side, Some(o), builtin, vec![None; n])
                }
                None => (
                    Side::Builtin(PolicyKind::Idle),
                    Some(PER_SCENARIO.to_owned()),
                    None,
                    scenario_opponents(&spec.scenarios)?,
                ),
            },
        };
        let drills = spec
            .scenarios
            .into_iter()
            .zip(kinds)
            .map(|(scenario, opponent)| Drill { scenario, opponent })
            .collect();
        let own = match spec.controlled {
            Controlled::Team(t) => t,
            Controlled::Both => Team::Blue,
        };
        Ok(VecMatches {
            setup: Arc::new(Setup {
                matches: spec.matches,
                robots: spec.controlled.robots(),
                cfg: spec.config,
                scale,
                decision: spec.decision,
                builtin,
                drills,
                cumulative,
                own,
                restart: spec.restart,
            }),
            opponent,
            opponent_spec,
            threads: spec.threads.max(1),
            slots: Vec::new(),
            stepper: None,
            panicked: None,
            opp_actions: Vec::new(),
        })
    }

    pub fn num_matches(&self) -> usize {
        self.setup.matches
    }

    /// The opponents' policy spec as resolved: the caller's; else the one
    /// every scenario names; else, the scenarios naming different built-in
    /// policies, [`PER_SCENARIO`] (each match plays its own scenario's);
    /// `scripted` without scenarios. `None` with [`Controlled::Both`].
    pub fn opponent(&self) -> Option<&str> {
        self.opponent_spec.as_deref()
    }

    /// Controlled robots per match.
    pub fn robots(&self) -> usize {
        self.setup.robots.len()
    }

    /// Actions per robot.
    pub fn actions(&self) -> usize {
        self.setup.actions()
    }

    /// Length of an observation row.
    pub fn obs_dim(&self) -> usize {
        self.setup.dim()
    }

    pub fn scale(&self) -> ObsScale {
        self.setup.scale
    }

    /// The action set and masks the robots decide under (`None`: the
    /// paper's five, never masked).
    pub fn decision(&self) -> Option<DecisionConfig> {
        self.setup.decision
    }

    /// Threads stepping the matches, the caller's included (the workers
    /// start at the first reset; never more than the matches).
    pub fn threads(&self) -> usize {
        self.threads.min(self.setup.matches)
    }

    /// Starts every slot's first match, slot `i` with seed `seed + i`, and
    /// writes their first observations and masks. A reset that fails
    /// changes nothing.
    pub fn reset(&mut self, seed: u64) -> Result<StepOut, VecEnvError> {
        let setup = &self.setup;
        let slots = (0..setup.matches)
            .map(|i| {
                let mut slot = new_slot(setup, i, seed, 0)?;
                slot.out = SlotOut::new(setup);
                write_rows(setup, slot.game.observations(), &mut slot.out);
                Ok(slot)
            })
            .collect::<Result<Vec<_>, VecEnvError>>()?;
        if self.stepper.is_none() {
            self.stepper = Some(Stepper::new(self.threads()).map_err(VecEnvError::Thread)?);
        }
        self.slots = slots;
        self.panicked = None;
        let mut out = StepOut::new(&self.setup);
        for (i, slot) in self.slots().enumerate() {
            out.copy_rows(i, &slot.out);
        }
        Ok(out)
    }

    /// Plays one control tick of every match: `actions` holds one action
    /// index per controlled robot, slot-major. Finished matches are reported
    /// in `finished` and restarted; `obs` and `masks` are then the new
    /// match's.
    pub fn step(&mut self, actions: &[i64]) -> Result<StepOut, VecEnvError> {
        let Some(stepper) = &self.stepper else {
            return Err(VecEnvError::Config("step before reset".into()));
        };
        if let Some(message) = &self.panicked {
            return Err(VecEnvError::Panicked(message.clone()));
        }
        let setup = &*self.setup;
        if let Some(slot) = self.slots.iter().position(|s| s.ended) {
            return Err(VecEnvError::Ended { slot });
        }
        let rows = setup.robots.len();
        let n_actions = setup.actions();
        if actions.len() != setup.matches * rows {
            return Err(VecEnvError::ActionCount {
                expected: setup.matches * rows,
                got: actions.len(),
            });
        }
        if let Some((robot, &value)) = actions
            .iter()
            .enumerate()
            .find(|(_, &a)| a < 0 || a as usize >= n_actions)
        {
            return Err(VecEnvError::Action {
                robot,
                value,
                actions: n_actions,
            });
        }
        let half = [setup.scale.half_length, setup.scale.half_width];
        let spot = setup
            .decision
            .map_or(SupportSpot::default(), |d| d.support_spot);
        for (slot, acts) in self.slots.iter_mut().zip(actions.chunks_exact(rows)) {
            for (r, &a) in setup.robots.iter().zip(acts) {
                let a = NetAction::from_index(a as usize).expect("actions are checked above");
                let a = to_action(
                    a,
                    &slot.game.observations()[r.index()],
                    half,
                    spot,
                    &setup.scale.kick,
                );
                slot.game.actions_mut()[r.index()] = a;
            }
        }
        // A trained opponent decides for all matches in one forward pass.
        if let (Side::Learned(policy), Controlled::Team(own)) =
            (&mut self.opponent, controlled_of(&setup.robots))
        {
            let team = own.other();
            let base = team.index() * PLAYERS_PER_TEAM;
            let teams: Vec<(u64, &[Observation])> = self
                .slots
                .iter()
                .map(|s| {
                    let g = &s.game;
                    (
                        g.match_ref().seed(),
                        &g.observations()[base..base + PLAYERS_PER_TEAM],
                    )
                })
                .collect();
            self.opp_actions.resize(teams.len() * PLAYERS_PER_TEAM, 0);
            policy.act_matches(&teams, &mut self.opp_actions);
            drop(teams);
            for (i, slot) in self.slots.iter_mut().enumerate() {
                for p in 0..PLAYERS_PER_TEAM {
                    let a = policy.action(
                        self.opp_actions[i * PLAYERS_PER_TEAM + p],
                        &slot.game.observations()[base + p],
                    );
                    slot.game.actions_mut()[base + p] = a;
                }
            }
        }
        // A panic is caught in its slot; the other slots still step.
        let panics =
            stepper.map(
                self.slots.iter_mut().collect(),
                |slot: &mut Slot| match catch_unwind(AssertUnwindSafe(|| step_slot(setup, slot))) {
                    Ok(r) => {
                        slot.out.error = r.err();
                        None
                    }
                    Err(payload) => Some(panic_message(&*payload)),
                },
            );
        if let Some(message) = panics.into_iter().flatten().next() {
            self.panicked = Some(message.clone());
            return Err(VecEnvError::Panicked(message));
        }
        let mut out = StepOut::new(setup);
        let mut error = None;
        for (i, slot) in self.slots.iter_mut().enumerate() {
            out.copy_rows(i, &slot.out);
            out.terminated[i] = slot.out.terminated;
            out.finished.extend(slot.out.finished.take());
            if let Some(e) = slot.out.error.take() {
                error.get_or_insert(e);
            }
        }
        match error {
            Some(e) => Err(e),
            None => Ok(out),
        }
    }

    /// The slots, in order (none before the first reset).
    fn slots(&self) -> impl Iterator<Item = &Slot> + '_ {
        self.slots.iter()
    }

    /// The state hash of each slot's current match.
    pub fn state_hashes(&self) -> Vec<u64> {
        self.slots()
            .map(|s| s.game.match_ref().state_hash())
            .collect()
    }

    /// Each slot's current match seed.
    pub fn seeds(&self) -> Vec<u64> {
        self.slots().map(|s| s.game.match_ref().seed()).collect()
    }

    /// The scenario each slot's current match started from, as its index
    /// in the list (`None` without scenarios).
    pub fn scenario_indices(&self) -> Vec<Option<usize>> {
        self.slots().map(|s| s.drill).collect()
    }

    /// Each slot's current tick.
    pub fn ticks(&self) -> Vec<u64> {
        self.slots()
            .map(|s| s.game.match_ref().tick().get())
            .collect()
    }

    /// Each slot's current score, as (blue, red).
    pub fn scores(&self) -> Vec<Score> {
        self.slots().map(|s| s.game.match_ref().score()).collect()
    }

    /// `f` of slot `slot`'s current match (as it ended, without restarts),
    /// `None` before the first reset or for a slot out of range.
    pub fn with_match<R>(&self, slot: usize, f: impl FnOnce(&Match) -> R) -> Option<R> {
        self.slots.get(slot).map(|s| f(s.game.match_ref()))
    }

    /// Appends each slot's global state ([`crate::state`], `STATE_DIM`
    /// values a slot) to `out`.
    pub fn write_states(&self, out: &mut Vec<f32>) {
        let player_0 = |t| RobotId::new(t, 0).expect("player 0 exists").index();
        let (b, r) = (player_0(Team::Blue), player_0(Team::Red));
        for slot in self.slots() {
            let at = out.len();
            out.resize(at + crate::state::STATE_DIM, 0.0);
            let scale = &self.setup.scale;
            let obs = slot.game.observations();
            crate::state::write_state(scale, &obs[b], &obs[r], &mut out[at..]);
        }
    }
}

fn controlled_of(robots: &[RobotId]) -> Controlled {
    if robots.len() == ROBOTS {
        Controlled::Both
    } else {
        Controlled::Team(robots[0].team())
    }
}

impl StepOut {
    fn new(s: &Setup) -> StepOut {
        let rows = s.matches * s.robots.len();
        StepOut {
            obs: vec![0.0; rows * s.dim()],
            rewards: vec![0.0; rows],
            terminated: vec![false; s.matches],
            masks: vec![true; rows * s.actions()],
            finished: Vec::new(),
        }
    }

    /// Copies slot `i`'s rows of observations, rewards and masks.
    fn copy_rows(&mut self, i: usize, slot: &SlotOut) {
        let at = |len: usize| i * len..(i + 1) * len;
        self.obs[at(slot.obs.len())].copy_from_slice(&slot.obs);
        self.rewards[at(slot.rewards.len())].copy_from_slice(&slot.rewards);
        self.masks[at(slot.masks.len())].copy_from_slice(&slot.masks);
    }
}

#[cfg(test)]
mod tests;

/// A caught panic's message.
fn panic_message(payload: &(dyn std::any::Any + Send)) -> String {
    if let Some(s) = payload.downcast_ref::<&str>() {
        (*s).to_owned()
    } else if let Some(s) = payload.downcast_ref::<String>() {
        s.clone()
    } else {
        "a panic without a message".to_owned()
    }
}
