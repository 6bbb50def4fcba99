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
//! --scenario FILE --own TEAM` plays.
//!
//! A finished match is reported once ([`Finished`]) and replaced at once by
//! the slot's next match: slot `i`'s `e`-th match (counting from the last
//! [`VecMatches::reset`] with seed `s`) has seed `s + i + e * n` for `n`
//! slots, so a slot's first match after `reset(s)` is `naosoccer match
//! --seed s+i`. Without [`EnvSpec::restart`] (the PettingZoo env: one
//! match, an episode that ends) a finished match stays as it ended, to be
//! looked at and drawn, and stepping refuses until the next reset.

use naosoccer_eval::eval::Side;
use naosoccer_policy::actions::{action_count, banned_actions, to_action, SupportSpot};
use naosoccer_policy::Policy;
use naosoccer_policy::{DecisionConfig, NetAction, ObsScale, PolicyError, OBS_DIM};
use naosoccer_proto::{
    Action, Event, MatchStats, Observation, RobotId, Score, Team, PLAYERS_PER_TEAM, ROBOTS,
};
use naosoccer_referee::{blank_observation, Judge, Match, MatchConfig, MatchError, Scenario};

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
    /// The other team's policy spec (ignored with [`Controlled::Both`]).
    pub opponent: String,
    pub config: MatchConfig,
    /// Observation layout version (1, 2 or 3).
    pub obs_version: u32,
    /// The action set and masks; `None`: the paper's five, none masked.
    pub decision: Option<DecisionConfig>,
    /// Worker threads for stepping (at least 1).
    pub threads: usize,
    /// Every match starts from this scenario (checked against `config`).
    pub scenario: Option<Scenario>,
    /// Whether a finished match is replaced by the slot's next one in the
    /// same step (the vector env) or stays finished until the next reset.
    pub restart: bool,
}

/// How a scenario's play ended: its end condition's name, whether that is
/// a success, and the control ticks played from the start.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ScenarioEnding {
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

struct Slot {
    m: Match,
    obs: Vec<Observation>,
    /// Built-in opponents, one per robot (`None`: driven by the caller or
    /// by a trained opponent).
    policies: Vec<Option<Box<dyn Policy>>>,
    actions: [Action; ROBOTS],
    /// Matches this slot finished since the last reset.
    episode: u64,
    /// With a scenario: the judge of this match's play, and the last
    /// tick's events it reads.
    judge: Option<Judge>,
    events: Vec<Event>,
    /// Finished and, without restarts, kept until the next reset.
    ended: bool,
}

/// The per-slot constants a worker thread needs.
struct Shape<'a> {
    cfg: &'a MatchConfig,
    robots: &'a [RobotId],
    scale: ObsScale,
    decision: Option<DecisionConfig>,
    actions: usize,
    dim: usize,
    opponent: &'a Side,
    slots: usize,
    seed: u64,
    /// The scenario and the colour of its own team.
    scenario: Option<&'a (Scenario, Team)>,
    restart: bool,
}

/// The [`Shape`] of `$env`, borrowing only the fields that stepping reads
/// (a method would borrow the slots too).
macro_rules! shape {
    ($env:expr) => {
        Shape {
            cfg: &$env.cfg,
            robots: &$env.robots,
            scale: $env.scale,
            decision: $env.decision,
            actions: action_count($env.decision),
            dim: $env.scale.dim(),
            opponent: &$env.opponent,
            slots: $env.matches,
            seed: $env.seed,
            scenario: $env.scenario.as_ref(),
            restart: $env.restart,
        }
    };
}

/// N matches stepped together.
pub struct VecMatches {
    matches: usize,
    cfg: MatchConfig,
    robots: Vec<RobotId>,
    scale: ObsScale,
    decision: Option<DecisionConfig>,
    opponent: Side,
    threads: usize,
    seed: u64,
    slots: Vec<Slot>,
    /// Action indices per row, kept to hand a trained opponent its share.
    opp_actions: Vec<usize>,
    scenario: Option<(Scenario, Team)>,
    restart: bool,
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
        let opponent = match spec.controlled {
            Controlled::Both => Side::Builtin(naosoccer_policy::PolicyKind::Idle),
            Controlled::Team(_) => Side::parse(&spec.opponent)?,
        };
        let scenario = match spec.scenario {
            Some(s) => {
                s.check(&spec.config).map_err(MatchError::from)?;
                let own = match spec.controlled {
                    Controlled::Team(t) => t,
                    Controlled::Both => Team::Blue,
                };
                Some((s, own))
            }
            None => None,
        };
        Ok(VecMatches {
            matches: spec.matches,
            robots: spec.controlled.robots(),
            cfg: spec.config,
            scale,
            decision: spec.decision,
            opponent,
            threads: spec.threads.max(1),
            seed: 0,
            slots: Vec::new(),
            opp_actions: Vec::new(),
            scenario,
            restart: spec.restart,
        })
    }

    pub fn num_matches(&self) -> usize {
        self.matches
    }

    /// Controlled robots per match.
    pub fn robots(&self) -> usize {
        self.robots.len()
    }

    /// Actions per robot.
    pub fn actions(&self) -> usize {
        action_count(self.decision)
    }

    /// Length of an observation row.
    pub fn obs_dim(&self) -> usize {
        self.scale.dim()
    }

    pub fn scale(&self) -> ObsScale {
        self.scale
    }

    /// The action set and masks the robots decide under (`None`: the
    /// paper's five, never masked).
    pub fn decision(&self) -> Option<DecisionConfig> {
        self.decision
    }

    /// Starts every slot's first match, slot `i` with seed `seed + i`, and
    /// writes their first observations and masks.
    pub fn reset(&mut self, seed: u64) -> Result<StepOut, VecEnvError> {
        self.seed = seed;
        self.slots.clear();
        let shape = shape!(self);
        let slots = (0..shape.slots)
            .map(|i| new_slot(&shape, i, 0))
            .collect::<Result<Vec<_>, _>>()?;
        let mut out = StepOut::default();
        out.resize(&shape);
        for (i, slot) in slots.iter().enumerate() {
            write_rows(&shape, slot, i, &mut out.obs, &mut out.masks);
        }
        self.slots = slots;
        Ok(out)
    }

    /// Plays one control tick of every match: `actions` holds one action
    /// index per controlled robot, slot-major. Finished matches are reported
    /// in `finished` and restarted; `obs` and `masks` are then the new
    /// match's.
    pub fn step(&mut self, actions: &[i64]) -> Result<StepOut, VecEnvError> {
        if self.slots.len() != self.matches {
            return Err(VecEnvError::Config("step before reset".into()));
        }
        if let Some(slot) = self.slots.iter().position(|s| s.ended) {
            return Err(VecEnvError::Ended { slot });
        }
        let rows = self.robots.len();
        let n_actions = self.actions();
        if actions.len() != self.matches * rows {
            return Err(VecEnvError::ActionCount {
                expected: self.matches * rows,
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
        let half = [self.scale.half_length, self.scale.half_width];
        let spot = self
            .decision
            .map_or(SupportSpot::default(), |d| d.support_spot);
        for (slot, acts) in self.slots.iter_mut().zip(actions.chunks_exact(rows)) {
            for (r, &a) in self.robots.iter().zip(acts) {
                let a = NetAction::from_index(a as usize).expect("actions are checked above");
                slot.actions[r.index()] = to_action(a, &slot.obs[r.index()], half, spot);
            }
        }
        // A trained opponent decides for all matches in one forward pass.
        if let (Side::Learned(policy), Controlled::Team(own)) =
            (&mut self.opponent, controlled_of(&self.robots))
        {
            let team = own.other();
            let base = team.index() * PLAYERS_PER_TEAM;
            let teams: Vec<(u64, &[Observation])> = self
                .slots
                .iter()
                .map(|s| (s.m.seed(), &s.obs[base..base + PLAYERS_PER_TEAM]))
                .collect();
            self.opp_actions.resize(teams.len() * PLAYERS_PER_TEAM, 0);
            policy.act_matches(&teams, &mut self.opp_actions);
            for (i, slot) in self.slots.iter_mut().enumerate() {
                for p in 0..PLAYERS_PER_TEAM {
                    let a = policy.action(
                        self.opp_actions[i * PLAYERS_PER_TEAM + p],
                        &slot.obs[base + p],
                    );
                    slot.actions[base + p] = a;
                }
            }
        }
        let shape = shape!(self);
        let mut out = StepOut::default();
        out.resize(&shape);
        let threads = self.threads.clamp(1, shape.slots);
        let per = shape.slots.div_ceil(threads);
        let (dim, acts) = (shape.dim, shape.actions);
        let results: Vec<Result<Vec<Finished>, VecEnvError>> = if threads == 1 {
            vec![step_chunk(
                &shape,
                0,
                &mut self.slots,
                &mut out.obs,
                &mut out.rewards,
                &mut out.terminated,
                &mut out.masks,
            )]
        } else {
            std::thread::scope(|s| {
                let shape = &shape;
                let mut chunks = self
                    .slots
                    .chunks_mut(per)
                    .zip(out.obs.chunks_mut(per * rows * dim))
                    .zip(out.rewards.chunks_mut(per * rows))
                    .zip(out.terminated.chunks_mut(per))
                    .zip(out.masks.chunks_mut(per * rows * acts))
                    .enumerate();
                // This thread steps the first chunk itself: one spawn fewer
                // per step, and it would only wait otherwise.
                let (_, ((((slots, obs), rewards), term), masks)) =
                    chunks.next().expect("at least one slot");
                let handles: Vec<_> = chunks
                    .map(|(k, ((((slots, obs), rewards), term), masks))| {
                        s.spawn(move || {
                            step_chunk(shape, k * per, slots, obs, rewards, term, masks)
                        })
                    })
                    .collect();
                let mut results = vec![step_chunk(shape, 0, slots, obs, rewards, term, masks)];
                results.extend(
                    handles
                        .into_iter()
                        .map(|h| h.join().expect("a stepping thread panicked")),
                );
                results
            })
        };
        for r in results {
            out.finished.extend(r?);
        }
        Ok(out)
    }

    /// The state hash of each slot's current match.
    pub fn state_hashes(&self) -> Vec<u64> {
        self.slots.iter().map(|s| s.m.state_hash()).collect()
    }

    /// Each slot's current match seed.
    pub fn seeds(&self) -> Vec<u64> {
        self.slots.iter().map(|s| s.m.seed()).collect()
    }

    /// Each slot's current tick.
    pub fn ticks(&self) -> Vec<u64> {
        self.slots.iter().map(|s| s.m.tick().get()).collect()
    }

    /// Each slot's current score, as (blue, red).
    pub fn scores(&self) -> Vec<Score> {
        self.slots.iter().map(|s| s.m.score()).collect()
    }

    /// Slot `slot`'s current match (as it ended, without restarts), `None`
    /// before the first reset or for a slot out of range.
    pub fn current(&self, slot: usize) -> Option<&Match> {
        self.slots.get(slot).map(|s| &s.m)
    }

    /// Appends each slot's global state ([`crate::state`], `STATE_DIM`
    /// values a slot) to `out`.
    pub fn write_states(&self, out: &mut Vec<f32>) {
        let player_0 = |t| RobotId::new(t, 0).expect("player 0 exists").index();
        let (b, r) = (player_0(Team::Blue), player_0(Team::Red));
        for slot in &self.slots {
            let at = out.len();
            out.resize(at + crate::state::STATE_DIM, 0.0);
            crate::state::write_state(&self.scale, &slot.obs[b], &slot.obs[r], &mut out[at..]);
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
    fn resize(&mut self, s: &Shape) {
        let rows = s.slots * s.robots.len();
        self.obs.resize(rows * s.dim, 0.0);
        self.rewards.resize(rows, 0.0);
        self.terminated.resize(s.slots, false);
        self.masks.resize(rows * s.actions, true);
    }
}

fn match_seed(shape: &Shape, slot: usize, episode: u64) -> u64 {
    shape
        .seed
        .wrapping_add(slot as u64)
        .wrapping_add(episode.wrapping_mul(shape.slots as u64))
}

fn new_slot(shape: &Shape, index: usize, episode: u64) -> Result<Slot, VecEnvError> {
    let seed = match_seed(shape, index, episode);
    let (m, judge) = match shape.scenario {
        Some((s, own)) => {
            let m = Match::with_scenario(shape.cfg, seed, s, *own)?;
            let judge = s.judge(shape.cfg, *own, m.tick());
            (m, Some(judge))
        }
        None => (Match::new(shape.cfg, seed)?, None),
    };
    let policies = RobotId::all()
        .map(|r| match shape.opponent {
            Side::Builtin(k) if !shape.robots.contains(&r) => Some(k.build(seed, r)),
            _ => None,
        })
        .collect();
    let mut slot = Slot {
        m,
        obs: (0..ROBOTS).map(|_| blank_observation()).collect(),
        policies,
        actions: [Action::Stay; ROBOTS],
        episode,
        judge,
        events: Vec::new(),
        ended: false,
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

/// Writes slot `index`'s rows of observations and masks (`obs` and `masks`
/// are the whole chunk's buffers, `index` counts within the chunk).
fn write_rows(shape: &Shape, slot: &Slot, index: usize, obs: &mut [f32], masks: &mut [bool]) {
    let rows = shape.robots.len();
    let mut row = [0.0f32; OBS_DIM];
    for (k, r) in shape.robots.iter().enumerate() {
        let o = &slot.obs[r.index()];
        let at = index * rows + k;
        shape.scale.encode(o, &mut row);
        obs[at * shape.dim..(at + 1) * shape.dim].copy_from_slice(&row[..shape.dim]);
        let mask = &mut masks[at * shape.actions..(at + 1) * shape.actions];
        mask.fill(true);
        if let Some(d) = &shape.decision {
            let in_reach = shape.scale.kick.in_reach(o);
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

fn step_chunk(
    shape: &Shape,
    first: usize,
    slots: &mut [Slot],
    obs: &mut [f32],
    rewards: &mut [f32],
    terminated: &mut [bool],
    masks: &mut [bool],
) -> Result<Vec<Finished>, VecEnvError> {
    let rows = shape.robots.len();
    let mut finished = Vec::new();
    for (i, slot) in slots.iter_mut().enumerate() {
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
        for (k, r) in shape.robots.iter().enumerate() {
            rewards[i * rows + k] = slot.m.reward(r.team(), r.player());
        }
        observe_all(slot);
        if slot.m.is_finished() || ending.is_some() {
            terminated[i] = true;
            write_rows(shape, slot, i, obs, masks);
            let index = first + i;
            finished.push(Finished {
                slot: index,
                seed: slot.m.seed(),
                ticks: slot.m.tick().get(),
                score: slot.m.score(),
                stats: slot.m.stats(),
                state_hash: slot.m.state_hash(),
                obs: obs[i * rows * shape.dim..(i + 1) * rows * shape.dim].to_vec(),
                scenario: ending.map(|e| ScenarioEnding {
                    ending: e.kind.name(),
                    success: e.success,
                    ticks: e.ticks,
                }),
            });
            if !shape.restart {
                slot.ended = true;
                continue;
            }
            *slot = new_slot(shape, index, slot.episode + 1)?;
        }
        write_rows(shape, slot, i, obs, masks);
    }
    Ok(finished)
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
            opponent: opponent.into(),
            config,
            obs_version: 2,
            decision: None,
            threads: 2,
            scenario: None,
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
        let m = env.current(0).unwrap();
        assert!(m.is_finished());
        assert_eq!(m.state_hash(), finished[0].state_hash);
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
        s.scenario = Some(scenario.clone());
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
        bad.scenario = Some(Scenario::from_toml("[ball]\nx = 4.0\ny = 0\n", None).unwrap());
        let e = VecMatches::new(bad).err().unwrap().to_string();
        assert!(e.contains("`ball.x`"), "{e}");
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
}
