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
//! The slots are stepped by a [`Pool`] of threads started at the first
//! reset and stopped when the env is dropped: every slot is stepped on its
//! own, so the matches come out the same whatever the number of threads.

use std::sync::{Arc, MutexGuard};

use naosoccer_eval::eval::Side;
use naosoccer_policy::actions::{action_count, banned_actions, to_action, SupportSpot};
use naosoccer_policy::{DecisionConfig, NetAction, ObsScale, PolicyError, OBS_DIM};
use naosoccer_policy::{Policy, PolicyKind};
use naosoccer_proto::{
    Action, Event, MatchStats, Observation, RobotId, Score, Team, PLAYERS_PER_TEAM, ROBOTS,
};
use naosoccer_referee::{blank_observation, Judge, Match, MatchConfig, MatchError, Scenario};
use rand::{RngCore, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::pool::Pool;

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

/// What every slot's matches are played under, fixed for the env's life
/// and shared with the stepping threads.
struct Setup {
    matches: usize,
    cfg: MatchConfig,
    robots: Vec<RobotId>,
    scale: ObsScale,
    decision: Option<DecisionConfig>,
    /// The built-in policy of the robots the caller does not drive (`None`:
    /// a trained team, which the env's own thread runs for all slots, or
    /// each scenario's own).
    builtin: Option<PolicyKind>,
    /// The scenarios a match may start from (none: the kick-off).
    drills: Vec<Drill>,
    /// The running sums of the scenarios' weights, the last their total.
    cumulative: Vec<f64>,
    /// The colour of the scenarios' own team.
    own: Team,
    restart: bool,
}

/// A scenario of the list.
struct Drill {
    scenario: Scenario,
    /// Its own opponents, when the scenarios name different built-in ones
    /// and the caller named none.
    opponent: Option<PolicyKind>,
}

/// What `opponent` reports when every match plays its own scenario's
/// `opponent` (the scenarios name different built-in policies).
pub const PER_SCENARIO: &str = "per scenario";

/// The stream of the scenario choice: the match seed mixed with this seeds
/// its generator, another stream than the scenario's own draws (the
/// referee's), so the start a scenario draws is the same chosen from a list
/// or played alone.
const PICK_STREAM: u64 = 0xC401_CE5D_A11E_5EED;

impl Setup {
    fn actions(&self) -> usize {
        action_count(self.decision)
    }

    fn dim(&self) -> usize {
        self.scale.dim()
    }
}

struct Slot {
    /// The slot's index and the seed of the last reset: with `episode`,
    /// the current match's seed.
    index: usize,
    reset_seed: u64,
    m: Match,
    obs: Vec<Observation>,
    /// Built-in opponents, one per robot (`None`: driven by the caller or
    /// by a trained opponent).
    policies: Vec<Option<Box<dyn Policy>>>,
    actions: [Action; ROBOTS],
    /// Matches this slot finished since the last reset.
    episode: u64,
    /// The scenario the match started from (its index in the list).
    drill: Option<usize>,
    /// With a scenario: the judge of this match's play, and the last
    /// tick's events it reads.
    judge: Option<Judge>,
    events: Vec<Event>,
    /// Finished and, without restarts, kept until the next reset.
    ended: bool,
    /// What the last reset or step wrote for this slot, kept from match to
    /// match so that stepping allocates nothing.
    out: SlotOut,
}

/// One slot's share of a [`StepOut`], and what went wrong stepping it.
#[derive(Default)]
struct SlotOut {
    obs: Vec<f32>,
    rewards: Vec<f32>,
    masks: Vec<bool>,
    terminated: bool,
    finished: Option<Finished>,
    error: Option<VecEnvError>,
}

impl SlotOut {
    fn new(setup: &Setup) -> SlotOut {
        let rows = setup.robots.len();
        SlotOut {
            obs: vec![0.0; rows * setup.dim()],
            rewards: vec![0.0; rows],
            masks: vec![true; rows * setup.actions()],
            terminated: false,
            finished: None,
            error: None,
        }
    }
}

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
    /// The slots and the threads that step them, from the first reset on.
    pool: Option<Pool<Slot>>,
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
            pool: None,
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
                write_rows(setup, &slot.obs, &mut slot.out);
                Ok(slot)
            })
            .collect::<Result<Vec<_>, VecEnvError>>()?;
        match &self.pool {
            Some(pool) => {
                for (i, slot) in slots.into_iter().enumerate() {
                    *pool.lock(i) = slot;
                }
            }
            None => {
                let setup = Arc::clone(setup);
                let pool = Pool::new(slots, self.threads, move |slot: &mut Slot| {
                    slot.out.error = step_slot(&setup, slot).err();
                })
                .map_err(VecEnvError::Thread)?;
                self.pool = Some(pool);
            }
        }
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
        let Some(pool) = &mut self.pool else {
            return Err(VecEnvError::Config("step before reset".into()));
        };
        if let Some(message) = &self.panicked {
            return Err(VecEnvError::Panicked(message.clone()));
        }
        let setup = &*self.setup;
        if let Some(slot) = (0..pool.len()).find(|&i| pool.lock(i).ended) {
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
        for (i, acts) in actions.chunks_exact(rows).enumerate() {
            let mut slot = pool.lock(i);
            let slot = &mut *slot;
            for (r, &a) in setup.robots.iter().zip(acts) {
                let a = NetAction::from_index(a as usize).expect("actions are checked above");
                slot.actions[r.index()] = to_action(a, &slot.obs[r.index()], half, spot);
            }
        }
        // A trained opponent decides for all matches in one forward pass.
        if let (Side::Learned(policy), Controlled::Team(own)) =
            (&mut self.opponent, controlled_of(&setup.robots))
        {
            let team = own.other();
            let base = team.index() * PLAYERS_PER_TEAM;
            let mut slots: Vec<MutexGuard<Slot>> = (0..pool.len()).map(|i| pool.lock(i)).collect();
            let teams: Vec<(u64, &[Observation])> = slots
                .iter()
                .map(|s| (s.m.seed(), &s.obs[base..base + PLAYERS_PER_TEAM]))
                .collect();
            self.opp_actions.resize(teams.len() * PLAYERS_PER_TEAM, 0);
            policy.act_matches(&teams, &mut self.opp_actions);
            drop(teams);
            for (i, slot) in slots.iter_mut().enumerate() {
                for p in 0..PLAYERS_PER_TEAM {
                    let a = policy.action(
                        self.opp_actions[i * PLAYERS_PER_TEAM + p],
                        &slot.obs[base + p],
                    );
                    slot.actions[base + p] = a;
                }
            }
        }
        if let Err(message) = pool.run() {
            self.panicked = Some(message.clone());
            return Err(VecEnvError::Panicked(message));
        }
        let mut out = StepOut::new(setup);
        let mut error = None;
        for i in 0..pool.len() {
            let mut slot = pool.lock(i);
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

    /// The slots, in order, each locked in turn (none before the first
    /// reset).
    fn slots(&self) -> impl Iterator<Item = MutexGuard<'_, Slot>> + '_ {
        let pool = self.pool.as_ref();
        (0..pool.map_or(0, |p| p.len())).filter_map(move |i| pool.map(|p| p.lock(i)))
    }

    /// The state hash of each slot's current match.
    pub fn state_hashes(&self) -> Vec<u64> {
        self.slots().map(|s| s.m.state_hash()).collect()
    }

    /// Each slot's current match seed.
    pub fn seeds(&self) -> Vec<u64> {
        self.slots().map(|s| s.m.seed()).collect()
    }

    /// The scenario each slot's current match started from, as its index
    /// in the list (`None` without scenarios).
    pub fn scenario_indices(&self) -> Vec<Option<usize>> {
        self.slots().map(|s| s.drill).collect()
    }

    /// Each slot's current tick.
    pub fn ticks(&self) -> Vec<u64> {
        self.slots().map(|s| s.m.tick().get()).collect()
    }

    /// Each slot's current score, as (blue, red).
    pub fn scores(&self) -> Vec<Score> {
        self.slots().map(|s| s.m.score()).collect()
    }

    /// `f` of slot `slot`'s current match (as it ended, without restarts),
    /// `None` before the first reset or for a slot out of range.
    pub fn with_match<R>(&self, slot: usize, f: impl FnOnce(&Match) -> R) -> Option<R> {
        let pool = self.pool.as_ref()?;
        (slot < pool.len()).then(|| f(&pool.lock(slot).m))
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
            crate::state::write_state(scale, &slot.obs[b], &slot.obs[r], &mut out[at..]);
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

fn match_seed(setup: &Setup, slot: usize, reset_seed: u64, episode: u64) -> u64 {
    reset_seed
        .wrapping_add(slot as u64)
        .wrapping_add(episode.wrapping_mul(setup.matches as u64))
}

/// The running sums of the weights of `n` scenarios (`None`: 1 each),
/// once they are checked.
fn cumulative_weights(n: usize, weights: Option<Vec<f64>>) -> Result<Vec<f64>, VecEnvError> {
    let bad = |m: String| Err(VecEnvError::Config(format!("scenario_weights: {m}")));
    let weights = match weights {
        None => vec![1.0; n],
        Some(_) if n == 0 => return bad("given without a scenario".into()),
        Some(w) if w.len() != n => {
            return bad(format!(
                "{} given for {n} scenarios: one weight a scenario",
                w.len()
            ))
        }
        Some(w) => w,
    };
    if let Some((i, w)) = weights
        .iter()
        .enumerate()
        .find(|(_, w)| !(w.is_finite() && **w >= 0.0))
    {
        return bad(format!(
            "weight {i} is {w}: a weight is a finite number, 0 or more"
        ));
    }
    let cumulative: Vec<f64> = weights
        .iter()
        .scan(0.0, |sum, w| {
            *sum += w;
            Some(*sum)
        })
        .collect();
    if let Some(&total) = cumulative.last() {
        if total == 0.0 {
            return bad("all are 0: at least one must be positive".into());
        }
        if !total.is_finite() {
            return bad("their sum is not a finite number".into());
        }
    }
    Ok(cumulative)
}

/// The opponents' spec when every match plays the same: `opponent`; else
/// the one every scenario names; else `scripted` without scenarios.
/// `None`: the scenarios name different built-in policies, each match
/// plays its own scenario's; a trained team among them is refused.
fn resolve_opponent(
    opponent: Option<String>,
    scenarios: &[Scenario],
) -> Result<Option<String>, VecEnvError> {
    if let Some(o) = opponent {
        return Ok(Some(o));
    }
    let Some(first) = scenarios.first() else {
        return Ok(Some("scripted".to_owned()));
    };
    if scenarios.iter().all(|s| s.opponent == first.opponent) {
        return Ok(Some(first.opponent.clone()));
    }
    if let Some((i, s)) = scenarios
        .iter()
        .enumerate()
        .find(|(_, s)| !naosoccer_policy::is_builtin_spec(&s.opponent))
    {
        let named: Vec<&str> = scenarios.iter().map(|s| s.opponent.as_str()).collect();
        return Err(VecEnvError::Config(format!(
            "the scenarios name different opponents ({}) and scenario[{i}] ({}) names a \
             trained team, {:?}, which plays every match or none: pass opponent= to name \
             the policy every match's opponents play",
            named.join(", "),
            s.name,
            s.opponent
        )));
    }
    Ok(None)
}

/// Each scenario's own opponents, all built-in policies.
fn scenario_opponents(scenarios: &[Scenario]) -> Result<Vec<Option<PolicyKind>>, VecEnvError> {
    scenarios
        .iter()
        .enumerate()
        .map(|(i, s)| {
            s.opponent.parse::<PolicyKind>().map(Some).map_err(|e| {
                VecEnvError::Config(format!("scenario[{i}] ({}): opponent: {e}", s.name))
            })
        })
        .collect()
}

/// The scenario the match of `seed` starts from, as its index in the list:
/// with two or more, scenario `i` with chance `weight[i] / sum`, from a
/// uniform number in [0, 1) (the top 53 bits of the first 64-bit draw) of a
/// ChaCha8 generator seeded by `seed ^ PICK_STREAM`. `None` without
/// scenarios.
fn pick(setup: &Setup, seed: u64) -> Option<usize> {
    match setup.drills.len() {
        0 => None,
        1 => Some(0),
        _ => {
            let mut rng = ChaCha8Rng::seed_from_u64(seed ^ PICK_STREAM);
            let u = (rng.next_u64() >> 11) as f64 / (1u64 << 53) as f64;
            let total = *setup.cumulative.last()?;
            let x = u * total;
            // Rounding may carry `x` to the total: the last scenario with a
            // weight then, never one of weight 0.
            setup
                .cumulative
                .iter()
                .position(|&c| x < c)
                .or_else(|| setup.cumulative.iter().position(|&c| c >= total))
        }
    }
}

/// Slot `index`'s `episode`-th match after a reset with `reset_seed`, with
/// no buffers for its rows yet.
fn new_slot(
    setup: &Setup,
    index: usize,
    reset_seed: u64,
    episode: u64,
) -> Result<Slot, VecEnvError> {
    let seed = match_seed(setup, index, reset_seed, episode);
    let drill = pick(setup, seed);
    let (m, judge) = match drill {
        Some(d) => {
            let (s, own) = (&setup.drills[d].scenario, setup.own);
            let m = Match::with_scenario(&setup.cfg, seed, s, own)?;
            let judge = s.judge(&setup.cfg, own, m.tick());
            (m, Some(judge))
        }
        None => (Match::new(&setup.cfg, seed)?, None),
    };
    let builtin = drill
        .and_then(|d| setup.drills[d].opponent)
        .or(setup.builtin);
    let policies = RobotId::all()
        .map(|r| match builtin {
            Some(k) if !setup.robots.contains(&r) => Some(k.build(seed, r)),
            _ => None,
        })
        .collect();
    let mut slot = Slot {
        index,
        reset_seed,
        m,
        obs: (0..ROBOTS).map(|_| blank_observation()).collect(),
        policies,
        actions: [Action::Stay; ROBOTS],
        episode,
        drill,
        judge,
        events: Vec::new(),
        ended: false,
        out: SlotOut::default(),
    };
    observe_all(&mut slot);
    Ok(slot)
}

fn observe_all(slot: &mut Slot) {
    for r in RobotId::all() {
        slot.m
            .observe_into(r.team(), r.player(), &mut slot.obs[r.index()]);
    }
}

/// Writes a slot's rows of observations and masks from its robots'
/// observations.
fn write_rows(setup: &Setup, obs: &[Observation], out: &mut SlotOut) {
    let dim = setup.dim();
    let actions = setup.actions();
    let mut row = [0.0f32; OBS_DIM];
    for (k, r) in setup.robots.iter().enumerate() {
        let o = &obs[r.index()];
        setup.scale.encode(o, &mut row);
        out.obs[k * dim..(k + 1) * dim].copy_from_slice(&row[..dim]);
        let mask = &mut out.masks[k * actions..(k + 1) * actions];
        mask.fill(true);
        if let Some(d) = &setup.decision {
            let in_reach = setup.scale.kick.in_reach(o);
            let mut bans = banned_actions(o, in_reach, d);
            if d.mask_shoot && !in_reach {
                bans |= NetAction::Shoot.bit();
            }
            for (a, m) in mask.iter_mut().enumerate() {
                *m = bans & (1 << a) == 0;
            }
        }
    }
}

/// One control tick of one slot's match, on whichever thread takes it:
/// the built-in robots decide, the match steps, and the slot's rows, its
/// ending and, if it ended, its next match are written into the slot.
fn step_slot(setup: &Setup, slot: &mut Slot) -> Result<(), VecEnvError> {
    slot.out.terminated = false;
    slot.out.finished = None;
    for (k, p) in slot.policies.iter_mut().enumerate() {
        if let Some(p) = p {
            slot.actions[k] = p.act(&slot.obs[k]);
        }
    }
    let ending = match &slot.judge {
        Some(judge) => {
            slot.events.clear();
            slot.events.extend_from_slice(slot.m.step(&slot.actions));
            judge.check(&slot.m, &slot.events)
        }
        None => {
            slot.m.step(&slot.actions);
            None
        }
    };
    for (k, r) in setup.robots.iter().enumerate() {
        slot.out.rewards[k] = slot.m.reward(r.team(), r.player());
    }
    observe_all(slot);
    write_rows(setup, &slot.obs, &mut slot.out);
    if slot.m.is_finished() || ending.is_some() {
        slot.out.terminated = true;
        slot.out.finished = Some(Finished {
            slot: slot.index,
            seed: slot.m.seed(),
            ticks: slot.m.tick().get(),
            score: slot.m.score(),
            stats: slot.m.stats(),
            state_hash: slot.m.state_hash(),
            obs: slot.out.obs.clone(),
            scenario: ending.zip(slot.drill).map(|(e, d)| ScenarioEnding {
                name: setup.drills[d].scenario.name.clone(),
                ending: e.kind.name(),
                success: e.success,
                ticks: e.ticks,
            }),
        });
        if !setup.restart {
            slot.ended = true;
            return Ok(());
        }
        let mut next = new_slot(setup, slot.index, slot.reset_seed, slot.episode + 1)?;
        std::mem::swap(&mut next.out, &mut slot.out);
        *slot = next;
        write_rows(setup, &slot.obs, &mut slot.out);
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn spec(matches: usize, opponent: &str, minutes: f32) -> EnvSpec {
        let config = MatchConfig {
            minutes,
            ..MatchConfig::default()
        };
        EnvSpec {
            matches,
            controlled: Controlled::Team(Team::Blue),
            opponent: Some(opponent.into()),
            config,
            obs_version: 2,
            decision: None,
            threads: 2,
            scenarios: Vec::new(),
            scenario_weights: None,
            restart: true,
        }
    }

    #[test]
    fn a_slot_plays_the_runners_match_and_restarts() {
        let mut env = VecMatches::new(spec(3, "scripted", 0.1)).unwrap();
        let out = env.reset(40).unwrap();
        assert_eq!(out.obs.len(), 3 * 4 * env.obs_dim());
        let stay = vec![4i64; 12];
        let mut finished = Vec::new();
        while finished.is_empty() {
            let out = env.step(&stay).unwrap();
            finished = out.finished;
        }
        assert_eq!(finished.len(), 3, "equal matches end on the same tick");
        // The runner's match: blue idle (always `stay`), red scripted.
        for f in &finished {
            let m = Match::new(&spec(1, "", 0.1).config, f.seed).unwrap();
            let policies = RobotId::all()
                .map(|r| match r.team() {
                    Team::Blue => naosoccer_policy::PolicyKind::Idle.build(f.seed, r),
                    Team::Red => naosoccer_policy::PolicyKind::Scripted.build(f.seed, r),
                })
                .collect::<Vec<_>>();
            let hash = play(m, policies);
            assert_eq!(f.state_hash, hash, "slot {}", f.slot);
        }
        assert_eq!(env.seeds(), vec![43, 44, 45]);
        assert_eq!(env.ticks(), vec![0, 0, 0]);
    }

    fn play(mut m: Match, mut policies: Vec<Box<dyn Policy>>) -> u64 {
        let mut obs: Vec<Observation> = (0..ROBOTS).map(|_| blank_observation()).collect();
        let mut actions = [Action::Stay; ROBOTS];
        while !m.is_finished() {
            for r in RobotId::all() {
                m.observe_into(r.team(), r.player(), &mut obs[r.index()]);
                actions[r.index()] = policies[r.index()].act(&obs[r.index()]);
            }
            m.step(&actions);
        }
        m.state_hash()
    }

    /// Without restarts a finished match stays as it ended (the PettingZoo
    /// env draws and inspects it) and stepping is refused until a reset.
    #[test]
    fn without_restarts_a_finished_match_stays() {
        let mut s = spec(1, "scripted", 0.1);
        s.restart = false;
        let mut env = VecMatches::new(s).unwrap();
        env.reset(40).unwrap();
        let stay = vec![4i64; 4];
        let finished = loop {
            let out = env.step(&stay).unwrap();
            if !out.finished.is_empty() {
                assert_eq!(out.terminated, [true]);
                break out.finished;
            }
        };
        assert_eq!(finished[0].seed, 40);
        let (over, hash) = env
            .with_match(0, |m| (m.is_finished(), m.state_hash()))
            .unwrap();
        assert!(over);
        assert_eq!(hash, finished[0].state_hash);
        assert_eq!(env.seeds(), vec![40]);
        assert!(matches!(
            env.step(&stay),
            Err(VecEnvError::Ended { slot: 0 })
        ));
        env.reset(41).unwrap();
        assert_eq!(env.ticks(), vec![0]);
        env.step(&stay).unwrap();
        let mut state = Vec::new();
        env.write_states(&mut state);
        assert_eq!(state.len(), crate::state::STATE_DIM);
    }

    #[test]
    fn masks_follow_the_decision_config() {
        let mut s = spec(1, "idle", 0.1);
        s.decision = Some(
            serde_json::from_str(r#"{"persist": 1, "mask_shoot": true, "pass": true}"#).unwrap(),
        );
        let mut env = VecMatches::new(s).unwrap();
        assert_eq!(env.actions(), 6);
        let out = env.reset(1).unwrap();
        // At kick-off nobody has the ball in reach: no shoot, no pass.
        for row in out.masks.chunks(6) {
            assert_eq!(row, [true, true, true, false, true, false]);
        }
    }

    /// A scenario's match ends with its play: the match `naosoccer match
    /// --scenario FILE --own red` plays, then the slot restarts from the
    /// scenario with its next seed.
    #[test]
    fn a_scenario_match_ends_with_its_play_and_restarts() {
        let text = "duration = 3.0\n[ball]\nx = 2.5\ny = 0.0\nvx = 2.0\n\
                    [[robot]]\nside = \"own\"\nplayer = 1\nx = 0\ny = 1\n\
                    [[end]]\nwhen = \"goal_for\"\noutcome = \"success\"\n";
        let scenario = Scenario::from_toml(text, None).unwrap();
        let mut s = spec(2, "idle", 1.0);
        s.controlled = Controlled::Team(Team::Red);
        s.scenarios = vec![scenario.clone()];
        let cfg = s.config.clone();
        let mut env = VecMatches::new(s).unwrap();
        env.reset(9).unwrap();
        let stay = vec![4i64; 8];
        let mut finished = Vec::new();
        while finished.is_empty() {
            finished = env.step(&stay).unwrap().finished;
        }
        assert_eq!(finished.len(), 2);
        for f in &finished {
            let mut m = Match::with_scenario(&cfg, f.seed, &scenario, Team::Red).unwrap();
            let judge = scenario.judge(&cfg, Team::Red, m.tick());
            let ending = loop {
                let events = m.step(&[Action::Stay; ROBOTS]).to_vec();
                if let Some(e) = judge.check(&m, &events) {
                    break e;
                }
            };
            assert_eq!(f.state_hash, m.state_hash(), "slot {}", f.slot);
            assert_eq!(f.score.red, 1, "red, the own team, scored");
            assert_eq!(
                f.scenario,
                Some(ScenarioEnding {
                    name: "scenario".into(),
                    ending: "goal_for",
                    success: true,
                    ticks: ending.ticks
                })
            );
        }
        assert_eq!(env.seeds(), vec![11, 12]);
        assert_eq!(env.ticks(), vec![0, 0]);
        // A scenario that does not fit the configuration is refused.
        let mut bad = spec(1, "idle", 1.0);
        bad.scenarios = vec![Scenario::from_toml("[ball]\nx = 4.0\ny = 0\n", None).unwrap()];
        let e = VecMatches::new(bad).err().unwrap().to_string();
        assert!(e.contains("`ball.x`"), "{e}");
    }

    /// A short scenario (its play lasts half a second: 5 ticks) named
    /// `name`, the ball `x` m from the centre, the opponents `opponent`.
    fn drill(name: &str, x: f32, opponent: &str) -> Scenario {
        let text = format!(
            "name = \"{name}\"\nopponent = \"{opponent}\"\nduration = 0.5\n\
             [ball]\nx = {x}\ny = [-0.5, 0.5]\n\
             [[robot]]\nside = \"own\"\nplayer = 1\nx = 0\ny = [0.5, 1.5]\n"
        );
        Scenario::from_toml(&text, None).unwrap()
    }

    fn drills_spec(matches: usize, scenarios: Vec<Scenario>, weights: Option<Vec<f64>>) -> EnvSpec {
        let mut s = spec(matches, "idle", 1.0);
        s.scenarios = scenarios;
        s.scenario_weights = weights;
        s
    }

    /// The scenario a one-slot env's match of `seed` starts from.
    fn drawn(scenarios: &[Scenario], weights: Option<Vec<f64>>, seed: u64) -> usize {
        let mut env = VecMatches::new(drills_spec(1, scenarios.to_vec(), weights)).unwrap();
        env.reset(seed).unwrap();
        env.scenario_indices()[0].unwrap()
    }

    /// With a list every match start draws its scenario from its seed: the
    /// same in any slot, at a reset or a restart, with any threads; both
    /// are drawn; each start is the one the scenario draws alone; the
    /// finished match names its scenario.
    #[test]
    fn a_list_draws_a_scenario_per_match_start() {
        let list = vec![drill("near", 2.0, "idle"), drill("far", -2.0, "idle")];
        let cfg = spec(1, "idle", 1.0).config;
        // The start a match of `seed` made from scenario `d` alone.
        let start = |seed, d: usize| {
            Match::with_scenario(&cfg, seed, &list[d], Team::Blue)
                .unwrap()
                .state_hash()
        };
        let mut runs = Vec::new();
        for threads in [1, 3] {
            let mut s = drills_spec(3, list.clone(), None);
            s.threads = threads;
            let mut env = VecMatches::new(s).unwrap();
            assert_eq!(env.opponent(), Some("idle"));
            // (seed, scenario) of every match start, in order.
            let mut starts = Vec::new();
            for reset in [100u64, 200, 300, 400] {
                env.reset(reset).unwrap();
                let indices = env.scenario_indices();
                for ((seed, hash), d) in
                    env.seeds().into_iter().zip(env.state_hashes()).zip(indices)
                {
                    let d = d.unwrap();
                    assert_eq!(d, drawn(&list, None, seed), "seed {seed}");
                    assert_eq!(hash, start(seed, d), "seed {seed}");
                    starts.push((seed, d));
                }
                let mut finished = 0;
                for _ in 0..12 {
                    let before = env.scenario_indices();
                    let out = env.step(&[4; 12]).unwrap();
                    for f in &out.finished {
                        let ending = f.scenario.as_ref().unwrap();
                        assert_eq!(ending.name, list[before[f.slot].unwrap()].name);
                        assert_eq!(ending.ending, "time_up");
                        finished += 1;
                        // The restart drew again, from the slot's next seed.
                        let seed = env.seeds()[f.slot];
                        assert_eq!(seed, f.seed + 3);
                        let d = env.scenario_indices()[f.slot].unwrap();
                        assert_eq!(d, drawn(&list, None, seed), "restart, seed {seed}");
                        assert_eq!(env.state_hashes()[f.slot], start(seed, d));
                        starts.push((seed, d));
                    }
                }
                assert_eq!(finished, 6, "every slot's first two matches ended");
            }
            for d in [0, 1] {
                assert!(starts.iter().any(|s| s.1 == d), "{d} drawn: {starts:?}");
            }
            runs.push(starts);
        }
        assert_eq!(runs[0], runs[1], "the same with 1 and 3 threads");
    }

    /// A list of one plays as its scenario alone, bit for bit, whatever
    /// its weight; so does a list whose other scenarios weigh 0.
    #[test]
    fn a_list_of_one_is_the_scenario_alone() {
        let one = drill("one", 1.0, "scripted");
        let other = drill("other", -1.0, "scripted");
        let run = |scenarios: Vec<Scenario>, weights: Option<Vec<f64>>| {
            let mut s = drills_spec(2, scenarios, weights);
            s.opponent = None;
            let mut env = VecMatches::new(s).unwrap();
            assert_eq!(env.opponent(), Some("scripted"));
            env.reset(5).unwrap();
            let mut hashes = vec![env.state_hashes()];
            for _ in 0..12 {
                let out = env.step(&[0, 1, 3, 4, 4, 3, 1, 0]).unwrap();
                hashes.push(env.state_hashes());
                hashes.push(out.finished.iter().map(|f| f.state_hash).collect());
            }
            hashes
        };
        let alone = run(vec![one.clone()], None);
        let cfg = spec(1, "idle", 1.0).config;
        let start = |seed| {
            Match::with_scenario(&cfg, seed, &one, Team::Blue)
                .unwrap()
                .state_hash()
        };
        assert_eq!(alone[0], vec![start(5), start(6)]);
        assert_eq!(run(vec![one.clone()], Some(vec![3.5])), alone);
        assert_eq!(
            run(vec![one.clone(), other.clone()], Some(vec![1.0, 0.0])),
            alone
        );
        assert_eq!(run(vec![other, one], Some(vec![0.0, 2.0])), alone);
    }

    /// The weights set the chances; a scenario of weight 0 is never drawn.
    #[test]
    fn weights_set_the_chances() {
        let list = vec![
            drill("a", 1.0, "idle"),
            drill("b", 0.0, "idle"),
            drill("c", -1.0, "idle"),
        ];
        let mut env = VecMatches::new(drills_spec(50, list, Some(vec![3.0, 0.0, 1.0]))).unwrap();
        let mut counts = [0usize; 3];
        for reset in 0..20 {
            env.reset(reset * 1000).unwrap();
            for d in env.scenario_indices() {
                counts[d.unwrap()] += 1;
            }
        }
        assert_eq!(counts[1], 0, "{counts:?}");
        // 1000 draws of chance 3/4: 750 +- 14 (one standard deviation).
        assert!((690..=810).contains(&counts[0]), "{counts:?}");
    }

    /// Bad weights, entries that do not fit and opponents that cannot be
    /// told apart per match are refused, naming what is wrong.
    #[test]
    fn bad_lists_are_refused() {
        let two = || vec![drill("a", 1.0, "idle"), drill("b", -1.0, "scripted")];
        let error = |scenarios: Vec<Scenario>, weights: Option<Vec<f64>>| {
            VecMatches::new(drills_spec(1, scenarios, weights))
                .err()
                .map(|e| e.to_string())
                .unwrap_or_default()
        };
        for (weights, says) in [
            (vec![1.0], "1 given for 2 scenarios"),
            (vec![1.0, 2.0, 3.0], "3 given for 2 scenarios"),
            (vec![1.0, -1.0], "weight 1 is -1"),
            (vec![f64::NAN, 1.0], "weight 0 is NaN"),
            (vec![f64::INFINITY, 1.0], "weight 0 is inf"),
            (vec![0.0, 0.0], "all are 0"),
            (vec![f64::MAX, f64::MAX], "sum is not a finite number"),
        ] {
            let e = error(two(), Some(weights));
            assert!(
                e.starts_with("scenario_weights: ") && e.contains(says),
                "{e}"
            );
        }
        let e = error(Vec::new(), Some(vec![1.0]));
        assert_eq!(e, "scenario_weights: given without a scenario");
        let far = Scenario::from_toml("name = \"far\"\n[ball]\nx = 4.0\ny = 0\n", None).unwrap();
        let e = error(vec![drill("a", 1.0, "idle"), far], None);
        assert!(
            e.starts_with("scenario[1] (far): ") && e.contains("`ball.x`"),
            "{e}"
        );
        // Different built-in opponents: each match plays its scenario's.
        let mut s = drills_spec(1, two(), None);
        s.opponent = None;
        let env = VecMatches::new(s).unwrap();
        assert_eq!(env.opponent(), Some(PER_SCENARIO));
        // A trained team among them needs `opponent=`.
        let mut s = drills_spec(
            1,
            vec![drill("a", 1.0, "idle"), drill("t", 0.0, "ppo:nowhere")],
            None,
        );
        s.opponent = None;
        let e = VecMatches::new(s).err().unwrap().to_string();
        assert!(
            e.contains("scenario[1] (t)") && e.contains("pass opponent="),
            "{e}"
        );
        // Named, it plays every match; the scenarios' own are not read.
        let mut s = drills_spec(
            1,
            vec![drill("a", 1.0, "idle"), drill("t", 0.0, "ppo:nowhere")],
            None,
        );
        s.opponent = Some("random".into());
        assert_eq!(VecMatches::new(s).unwrap().opponent(), Some("random"));
        // Self-play has no opponents to choose.
        let mut s = drills_spec(
            1,
            vec![drill("a", 1.0, "idle"), drill("t", 0.0, "ppo:nowhere")],
            None,
        );
        s.opponent = None;
        s.controlled = Controlled::Both;
        assert_eq!(VecMatches::new(s).unwrap().opponent(), None);
    }

    /// With opponents per scenario each match plays its own scenario's: the
    /// match of an env of that scenario alone, opponents and all.
    #[test]
    fn each_match_plays_its_scenarios_opponents() {
        let list = vec![
            drill("idle", 1.0, "idle"),
            drill("scripted", 1.0, "scripted"),
        ];
        let mut s = drills_spec(6, list.clone(), None);
        s.opponent = None;
        let mut env = VecMatches::new(s).unwrap();
        env.reset(64).unwrap();
        for _ in 0..4 {
            env.step(&[4; 24]).unwrap();
        }
        let indices = env.scenario_indices();
        assert!(
            indices.contains(&Some(0)) && indices.contains(&Some(1)),
            "{indices:?}"
        );
        for (i, d) in indices.into_iter().enumerate() {
            let d = d.unwrap();
            let mut s = drills_spec(1, vec![list[d].clone()], None);
            s.opponent = None;
            let mut alone = VecMatches::new(s).unwrap();
            assert_eq!(alone.opponent(), Some(list[d].opponent.as_str()));
            alone.reset(64 + i as u64).unwrap();
            for _ in 0..4 {
                alone.step(&[4; 4]).unwrap();
            }
            assert_eq!(env.state_hashes()[i], alone.state_hashes()[0], "slot {i}");
        }
    }

    #[test]
    fn bad_actions_are_refused() {
        let mut env = VecMatches::new(spec(2, "random", 0.1)).unwrap();
        env.reset(0).unwrap();
        assert!(matches!(
            env.step(&[0; 7]),
            Err(VecEnvError::ActionCount {
                expected: 8,
                got: 7
            })
        ));
        let mut a = [0i64; 8];
        a[5] = 5;
        assert!(matches!(
            env.step(&a),
            Err(VecEnvError::Action { robot: 5, .. })
        ));
    }

    /// Everything a run of steps returns, bits and all.
    fn trace(threads: usize, steps: usize) -> Vec<String> {
        let mut s = spec(5, "scripted", 0.2);
        s.threads = threads;
        s.decision = Some(serde_json::from_str(r#"{"mask_shoot": true, "pass": true}"#).unwrap());
        let mut env = VecMatches::new(s).unwrap();
        assert_eq!(env.threads(), threads.min(5));
        let out = env.reset(7).unwrap();
        let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        let mut trace = vec![format!("{:?} {:?}", bits(&out.obs), out.masks)];
        // A fixed stream of valid actions (xorshift), the same for every run.
        let mut x = 0x9e37_79b9_7f4a_7c15u64;
        for _ in 0..steps {
            let actions: Vec<i64> = (0..20)
                .map(|_| {
                    x ^= x << 13;
                    x ^= x >> 7;
                    x ^= x << 17;
                    (x % 6) as i64
                })
                .collect();
            let out = env.step(&actions).unwrap();
            trace.push(format!(
                "{:?} {:?} {:?} {:?} {:?}",
                bits(&out.obs),
                bits(&out.rewards),
                out.terminated,
                out.masks,
                out.finished
                    .iter()
                    .map(|f| (f.slot, f.seed, f.ticks, f.state_hash, bits(&f.obs)))
                    .collect::<Vec<_>>()
            ));
            trace.push(format!("{:x?}", env.state_hashes()));
        }
        trace
    }

    /// The matches are the same, tick for tick and bit for bit, whatever the
    /// number of threads stepping them (five slots: shares that do not
    /// divide evenly; 300 steps: every slot's first match ends at 120 and
    /// its second at 240).
    #[test]
    fn threads_do_not_change_the_matches() {
        let one = trace(1, 300);
        assert!(one.iter().any(|t| t.contains("true")), "matches ended");
        for threads in [2, 3, 8] {
            let other = trace(threads, 300);
            let first = one.iter().zip(&other).position(|(a, b)| a != b);
            assert_eq!(
                first, None,
                "threads {threads}: the first entry that differs"
            );
        }
    }

    /// A policy that meets its twin of the other slot at a barrier before
    /// acting, so that the two slots are stepped at once, by two threads;
    /// the one that panics records which thread it ran on.
    struct Twin {
        barrier: Arc<std::sync::Barrier>,
        panics: Option<Arc<std::sync::Mutex<Option<String>>>>,
    }

    impl Policy for Twin {
        fn act(&mut self, _: &Observation) -> Action {
            self.barrier.wait();
            if let Some(thread) = &self.panics {
                *thread.lock().unwrap() = std::thread::current().name().map(String::from);
                panic!("a robot's policy failed");
            }
            Action::Stay
        }

        fn name(&self) -> &str {
            "twin"
        }
    }

    /// A panic on a stepping thread comes back as an error (not a hang, not
    /// a panic of the caller); stepping is refused until the next reset,
    /// which plays on with the same threads.
    #[test]
    fn a_panic_on_a_worker_is_an_error() {
        let mut env = VecMatches::new(spec(2, "idle", 0.1)).unwrap();
        env.reset(3).unwrap();
        let barrier = Arc::new(std::sync::Barrier::new(2));
        let thread = Arc::new(std::sync::Mutex::new(None));
        {
            let pool = env.pool.as_ref().unwrap();
            assert_eq!(pool.workers(), 1);
            // The caller takes slot 0 first and waits at the barrier for
            // slot 1, which only the worker can then be stepping.
            pool.lock(0).policies[4] = Some(Box::new(Twin {
                barrier: Arc::clone(&barrier),
                panics: None,
            }));
            pool.lock(1).policies[4] = Some(Box::new(Twin {
                barrier,
                panics: Some(Arc::clone(&thread)),
            }));
        }
        let stay = [4i64; 8];
        let e = env.step(&stay).err().unwrap();
        assert!(
            matches!(&e, VecEnvError::Panicked(m) if m == "a robot's policy failed"),
            "{e}"
        );
        assert_eq!(thread.lock().unwrap().as_deref(), Some("naosoccer-step-1"));
        assert!(matches!(env.step(&stay), Err(VecEnvError::Panicked(_))));
        env.reset(3).unwrap();
        env.step(&stay).unwrap();
        assert_eq!(env.ticks(), vec![1, 1]);
    }
}
