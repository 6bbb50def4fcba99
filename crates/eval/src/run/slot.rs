//! One match as every batch of matches steps it: the match, its built-in
//! robots, the observations and actions of its eight robots, and a
//! scenario's judge. [`super::Batch`] (evaluations, leagues, the academy,
//! the CLI's `match`), the learning crate's vectorised environment and the
//! Python package's vector env each hold one per match they play, and add
//! only what they report: results, rewards and encoded rows.
//!
//! A tick is always taken the same way ([`MatchSlot::step`]): the robots
//! not driven by a built-in team are given their actions first (a trained
//! team, a learner, a Python caller), then every built-in robot decides
//! from its observation, the match steps, the judge reads the tick's
//! events, and every robot observes the new state.

use naosoccer_policy::{Policy, PolicyKind};
use naosoccer_proto::{Action, Event, Observation, RobotId, Team, ROBOTS};
use naosoccer_referee::{Ending, Judge, Match, MatchConfig, MatchError, Scenario};

/// One match, its built-in robots and its robots' last observations.
pub struct MatchSlot {
    m: Match,
    judge: Option<Judge>,
    /// By robot index (blue 0..=3, red 0..=3).
    obs: Vec<Observation>,
    /// The built-in robots' policies, by robot index (`None`: a robot
    /// whose actions are given).
    policies: Vec<Option<Box<dyn Policy>>>,
    /// The actions of the last tick, or those given for the next one.
    actions: [Action; ROBOTS],
    /// The last tick's referee events.
    events: Vec<Event>,
}

impl MatchSlot {
    /// The match of `seed`, from the kick-off or from a scenario with its
    /// own team playing the given colour (then judged by the scenario's end
    /// conditions); every robot observes it. No robot is built in yet
    /// ([`MatchSlot::build_policies`]).
    pub fn new(
        cfg: &MatchConfig,
        seed: u64,
        scenario: Option<(&Scenario, Team)>,
    ) -> Result<MatchSlot, MatchError> {
        let (m, judge) = match scenario {
            Some((s, own)) => {
                let m = Match::with_scenario(cfg, seed, s, own)?;
                let judge = s.judge(cfg, own, m.tick());
                (m, Some(judge))
            }
            None => (Match::new(cfg, seed)?, None),
        };
        let mut slot = MatchSlot {
            m,
            judge,
            obs: (0..ROBOTS)
                .map(|_| naosoccer_referee::blank_observation())
                .collect(),
            policies: (0..ROBOTS).map(|_| None).collect(),
            actions: [Action::Stay; ROBOTS],
            events: Vec::with_capacity(16),
        };
        slot.observe_all();
        Ok(slot)
    }

    /// Builds the built-in robots afresh: robot `r` plays `kind(r)`
    /// (`None`: its actions are given), seeded by the match seed as the
    /// server and the robot clients seed them.
    pub fn build_policies(&mut self, mut kind: impl FnMut(RobotId) -> Option<PolicyKind>) {
        let seed = self.m.seed();
        for r in RobotId::all() {
            self.policies[r.index()] = kind(r).map(|k| k.build(seed, r));
        }
    }

    /// Robot `robot` plays `policy` from now on (`None`: its actions are
    /// given), in place of what [`MatchSlot::build_policies`] built.
    pub fn set_policy(&mut self, robot: RobotId, policy: Option<Box<dyn Policy>>) {
        self.policies[robot.index()] = policy;
    }

    /// Every robot observes the match as it is (after moving things by
    /// hand through [`MatchSlot::match_mut`]).
    pub fn observe_all(&mut self) {
        for r in RobotId::all() {
            self.m
                .observe_into(r.team(), r.player(), &mut self.obs[r.index()]);
        }
    }

    /// One control tick: the built-in robots decide (the others play what
    /// [`MatchSlot::actions_mut`] was given), the match steps, a
    /// scenario's end conditions are checked and every robot observes the
    /// new state. Returns the scenario's ending, if it came with this tick.
    pub fn step(&mut self) -> Option<Ending> {
        for (i, p) in self.policies.iter_mut().enumerate() {
            if let Some(p) = p {
                self.actions[i] = p.act(&self.obs[i]);
            }
        }
        // `step` lends its events out of the match; a copy into a reused
        // buffer lets the judge and a watcher read the match and the
        // events together.
        self.events.clear();
        self.events.extend_from_slice(self.m.step(&self.actions));
        let ending = self
            .judge
            .as_ref()
            .and_then(|j| j.check(&self.m, &self.events));
        self.observe_all();
        ending
    }

    pub fn match_ref(&self) -> &Match {
        &self.m
    }

    /// The match, to move things by hand (a drill's placements); call
    /// [`MatchSlot::observe_all`] after.
    pub fn match_mut(&mut self) -> &mut Match {
        &mut self.m
    }

    /// The robots' observations, by robot index.
    pub fn observations(&self) -> &[Observation] {
        &self.obs
    }

    /// The actions of the last tick, by robot index.
    pub fn actions(&self) -> &[Action; ROBOTS] {
        &self.actions
    }

    /// Where the actions of the robots that are not built in are given
    /// before [`MatchSlot::step`], by robot index.
    pub fn actions_mut(&mut self) -> &mut [Action; ROBOTS] {
        &mut self.actions
    }

    /// The last tick's referee events.
    pub fn events(&self) -> &[Event] {
        &self.events
    }

    /// Whether the match was started from a scenario (and is judged).
    pub fn is_judged(&self) -> bool {
        self.judge.is_some()
    }
}
