//! The vectorised environment: many `referee::Match`es in process, stepped
//! together, with the learning team's robots flattened into one batch.
//!
//! Row order everywhere: match-major, then learning robot (`m * L + k` for
//! match `m` and the `k`-th entry of `learners`). Each match lets the learner
//! play blue in even-numbered matches and red in odd ones; observations are
//! mirrored by the referee, so both sides look alike to the network.
//!
//! Matches are independent, so stepping them on several threads gives the
//! same results as on one: each match's seed depends only on the base seed,
//! its index and its episode number. Each is a
//! [`naosoccer_eval::run::MatchSlot`], built and stepped as evaluations and
//! the CLI build and step theirs, by the same threads (a
//! [`naosoccer_eval::run::Stepper`]); this module adds the learners' rows,
//! rewards, the opponents' mix and the episodes' restarts.
//!
//! Over it, [`decisions`] is the decision-level MDP the team presets learn
//! on: holds, masks and open decisions, each closed decision one transition.

use naosoccer_eval::run::{MatchSlot, Stepper};
use naosoccer_policy::PolicyKind;
use naosoccer_proto::{Action, Observation, RobotId, Team, PLAYERS_PER_TEAM};
use naosoccer_referee::{MatchConfig, Scenario};

use crate::obs::{ObsScale, OBS_DIM};
use crate::LearnError;

pub mod decisions;
mod drills;
mod opponents;
pub use drills::{Drill, ScenarioDrills, ScenarioText};
pub use naosoccer_policy::BatchActor;
use naosoccer_policy::{to_action, NetAction, SupportSpot};
use opponents::Mix;
pub use opponents::Opponent;

/// What one finished episode (a whole match) showed.
#[derive(Debug, Clone, PartialEq)]
pub struct Episode {
    pub match_index: usize,
    pub learner_team: Team,
    pub goals_for: u32,
    pub goals_against: u32,
    /// Sum of each learning robot's rewards, indexed like `learners`.
    pub returns: Vec<f32>,
    pub stats: naosoccer_proto::MatchStats,
    pub ticks: u64,
}

/// How the environment is laid out.
#[derive(Debug, Clone)]
pub struct EnvConfig {
    pub matches: usize,
    /// Players (0..4) the network controls; the others play `teammates`.
    pub learners: Vec<usize>,
    pub teammates: PolicyKind,
    /// Threads that step matches.
    pub threads: usize,
    pub seed: u64,
    /// Where a network's `support` walks to (the run's decision setting).
    pub support_spot: SupportSpot,
}

struct Slot {
    index: usize,
    /// The match, its built-in robots (none where a network decides) and
    /// the observations of all eight robots.
    game: MatchSlot,
    team: Team,
    episode: u64,
    returns: Vec<f32>,
    finished: Option<Episode>,
    /// Index of this episode's opponent.
    opp: usize,
    drill: Option<Drill>,
    /// This match plays episodes of these scenarios ([`ScenarioDrills`]),
    /// judged by their end conditions, and cuts them every `window_len`
    /// ticks.
    scenarios: Option<std::sync::Arc<Vec<Scenario>>>,
    /// Ticks since the matches last started together, and a match's length.
    window: u64,
    window_len: u64,
}

/// The vectorised environment.
pub struct VecEnv {
    cfg: MatchConfig,
    env: EnvConfig,
    scale: ObsScale,
    slots: Vec<Slot>,
    /// The opponents, and the weights each episode draws its opponent by.
    opponents: Vec<Opponent>,
    mix: Mix,
    /// Learner observation vectors, `[matches * L, OBS_DIM]`.
    feats: Vec<f32>,
    rewards: Vec<f32>,
    dones: Vec<bool>,
    /// Rows whose episode was cut (a scenario's end) with the last step.
    truncated: Vec<bool>,
    /// Those rows' observation vectors at the cut (before the restart).
    final_feats: Vec<f32>,
    /// Network opponents' actions, as their teams play them.
    opp_actions: Vec<Action>,
    ticks: u64,
    /// The threads stepping the matches.
    stepper: Stepper,
}

pub use naosoccer_eval::eval::{episode_seed, legacy_episode_seed};

impl VecEnv {
    pub fn new(
        cfg: &MatchConfig,
        env: EnvConfig,
        opponent: Opponent,
    ) -> Result<VecEnv, LearnError> {
        if env.matches == 0 {
            return Err(LearnError::Config("at least one match is needed".into()));
        }
        if env.learners.is_empty() || env.learners.iter().any(|&p| p >= PLAYERS_PER_TEAM) {
            return Err(LearnError::Config(format!(
                "learning players must be a non-empty subset of 0..{PLAYERS_PER_TEAM}, got {:?}",
                env.learners
            )));
        }
        let l = env.learners.len();
        let opponents = vec![opponent];
        let mix = Mix::new(&opponents, &[1.0])?;
        let mut slots = Vec::with_capacity(env.matches);
        for index in 0..env.matches {
            let team = if index % 2 == 0 {
                Team::Blue
            } else {
                Team::Red
            };
            let game = MatchSlot::new(cfg, episode_seed(env.seed, index, 0), None)?;
            let window_len = game.match_ref().total_ticks();
            let mut slot = Slot {
                index,
                returns: vec![0.0; l],
                game,
                team,
                episode: 0,
                finished: None,
                opp: 0,
                drill: None,
                scenarios: None,
                window: 0,
                window_len,
            };
            slot.build_policies(&env, &mix);
            slots.push(slot);
        }
        let scale = ObsScale::from_config(cfg);
        let stepper = Stepper::new(env.threads.clamp(1, env.matches)).map_err(|e| {
            LearnError::Config(format!("cannot start the threads stepping matches: {e}"))
        })?;
        let mut venv = VecEnv {
            cfg: cfg.clone(),
            feats: vec![0.0; env.matches * l * OBS_DIM],
            rewards: vec![0.0; env.matches * l],
            dones: vec![false; env.matches * l],
            truncated: vec![false; env.matches * l],
            final_feats: vec![0.0; env.matches * l * OBS_DIM],
            opp_actions: vec![Action::Stay; env.matches * PLAYERS_PER_TEAM],
            stepper,
            env,
            scale,
            slots,
            opponents,
            mix,
            ticks: 0,
        };
        for (slot, f) in venv.slots.iter().zip(venv.feats.chunks_mut(l * OBS_DIM)) {
            slot.encode_learners(&venv.env.learners, &venv.scale, f);
        }
        Ok(venv)
    }

    /// Rows in every batch: matches times learning robots.
    pub fn rows(&self) -> usize {
        self.env.matches * self.env.learners.len()
    }

    pub fn learners(&self) -> &[usize] {
        &self.env.learners
    }

    pub fn scale(&self) -> ObsScale {
        self.scale
    }

    pub fn match_config(&self) -> &MatchConfig {
        &self.cfg
    }

    /// Control ticks stepped so far, summed over matches.
    pub fn ticks(&self) -> u64 {
        self.ticks
    }

    /// The current observation vectors, `[rows, OBS_DIM]`.
    pub fn observations(&self) -> &[f32] {
        &self.feats
    }

    /// Rewards of the last step, per row.
    pub fn rewards(&self) -> &[f32] {
        &self.rewards
    }

    /// Whether each row's episode ended with the last step (its observation
    /// is then already the first of the next episode).
    pub fn dones(&self) -> &[bool] {
        &self.dones
    }

    /// Whether each row's episode ended with the last step by being cut (a
    /// scenario's end, [`ScenarioDrills`]) rather than by the match's end:
    /// its last transition is then bootstrapped from [`Self::final_observations`].
    pub fn truncated(&self) -> &[bool] {
        &self.truncated
    }

    /// For the rows [`Self::truncated`] by the last step: their observation
    /// vectors in the state where the episode was cut, `[rows, OBS_DIM]`
    /// (other rows hold stale values).
    pub fn final_observations(&self) -> &[f32] {
        &self.final_feats
    }

    /// Encodes observations with `scale` from now on (e.g. an older layout
    /// version); re-encodes the current ones.
    pub fn set_obs_scale(&mut self, scale: ObsScale) {
        self.scale = scale;
        let l = self.env.learners.len();
        for (slot, f) in self.slots.iter().zip(self.feats.chunks_mut(l * OBS_DIM)) {
            slot.encode_learners(&self.env.learners, &self.scale, f);
        }
    }

    /// The observation row `row` was encoded from (the learning robot's
    /// last observation; after an episode's end, the next episode's first).
    pub fn learner_observation(&self, row: usize) -> &Observation {
        let l = self.env.learners.len();
        let slot = &self.slots[row / l];
        &slot.game.observations()[slot.team.index() * PLAYERS_PER_TEAM + self.env.learners[row % l]]
    }

    /// Whether row `row`'s robot is in play (not absent from the scenario
    /// its match started from).
    pub fn in_play(&self, row: usize) -> bool {
        let l = self.env.learners.len();
        let slot = &self.slots[row / l];
        let robot = RobotId::new(slot.team, self.env.learners[row % l])
            .expect("learners are players of a team");
        !slot.game.match_ref().is_out_of_play(robot)
    }

    /// Replaces the opponent (self-play: a newer snapshot).
    pub fn set_opponent(&mut self, opponent: Opponent) {
        self.set_opponents(vec![opponent], &[1.0])
            .expect("one opponent of weight 1 is a valid mix");
    }

    /// Replaces the opponents: from now on each episode plays one of them,
    /// drawn by `weights`; the matches under way draw theirs again now.
    pub fn set_opponents(
        &mut self,
        opponents: Vec<Opponent>,
        weights: &[f64],
    ) -> Result<(), LearnError> {
        self.mix = Mix::new(&opponents, weights)?;
        self.opponents = opponents;
        for slot in &mut self.slots {
            slot.build_policies(&self.env, &self.mix);
        }
        Ok(())
    }

    /// Starts every match afresh at episode `episodes[i]` (as if that many
    /// had finished), the tick counter at `ticks`: where a resumed run picks
    /// up, at an episode boundary.
    pub fn restart_at(&mut self, episodes: &[u64], ticks: u64) -> Result<(), LearnError> {
        if episodes.len() != self.slots.len() {
            return Err(LearnError::Config(format!(
                "{} episode numbers for {} matches",
                episodes.len(),
                self.slots.len()
            )));
        }
        let l = self.env.learners.len();
        for (slot, &e) in self.slots.iter_mut().zip(episodes) {
            slot.episode = e;
            slot.window = 0;
            slot.start_episode(&self.cfg, &self.env)?;
            slot.returns = vec![0.0; l];
            slot.finished = None;
            slot.build_policies(&self.env, &self.mix);
            slot.game.observe_all();
        }
        for (slot, f) in self.slots.iter().zip(self.feats.chunks_mut(l * OBS_DIM)) {
            slot.encode_learners(&self.env.learners, &self.scale, f);
        }
        self.ticks = ticks;
        Ok(())
    }

    /// Each match's episode number (how many of its episodes finished).
    pub fn episodes(&self) -> Vec<u64> {
        self.slots.iter().map(|s| s.episode).collect()
    }

    /// Applies one action per row and steps every match one control tick;
    /// finished matches restart with their next episode's seed. Returns the
    /// episodes that ended.
    pub fn step(&mut self, actions: &[usize]) -> Result<Vec<Episode>, LearnError> {
        self.step_beside(actions, || {})
    }

    /// [`VecEnv::step`], the caller's thread running `beside` first while
    /// the other threads start stepping (work of the caller's that the
    /// tick does not wait for, such as the critic's values of the
    /// decisions just taken); then it steps its share of the matches.
    pub fn step_beside(
        &mut self,
        actions: &[usize],
        beside: impl FnOnce(),
    ) -> Result<Vec<Episode>, LearnError> {
        let l = self.env.learners.len();
        assert_eq!(actions.len(), self.rows(), "one action per learning robot");
        let mut teams: Vec<(u64, &[Observation])> = Vec::new();
        let mut at: Vec<usize> = Vec::new();
        let mut acts: Vec<usize> = Vec::new();
        for (k, opponent) in self.opponents.iter_mut().enumerate() {
            let Opponent::Net(actor) = opponent else {
                continue;
            };
            teams.clear();
            at.clear();
            for (j, slot) in self.slots.iter().enumerate().filter(|(_, s)| s.opp == k) {
                let base = slot.team.other().index() * PLAYERS_PER_TEAM;
                let g = &slot.game;
                teams.push((
                    g.match_ref().seed(),
                    &g.observations()[base..base + PLAYERS_PER_TEAM],
                ));
                at.push(j);
            }
            if teams.is_empty() {
                continue;
            }
            acts.resize(teams.len() * PLAYERS_PER_TEAM, 0);
            actor.act_teams(&teams, &mut acts);
            // Each index becomes the step its own team takes (a `support`
            // toward its own support spot), from the observation it acted on.
            for (i, (&j, (_, obs))) in at.iter().zip(&teams).enumerate() {
                for p in 0..PLAYERS_PER_TEAM {
                    self.opp_actions[j * PLAYERS_PER_TEAM + p] =
                        actor.action(acts[i * PLAYERS_PER_TEAM + p], &obs[p]);
                }
            }
        }
        let cfg = &self.cfg;
        let env = &self.env;
        let scale = &self.scale;
        let mix = &self.mix;
        // One work item a match: the match and its rows of every buffer.
        let work: Vec<_> = self
            .slots
            .iter_mut()
            .zip(actions.chunks(l))
            .zip(self.opp_actions.chunks(PLAYERS_PER_TEAM))
            .zip(self.feats.chunks_mut(l * OBS_DIM))
            .zip(self.rewards.chunks_mut(l))
            .zip(self.dones.chunks_mut(l))
            .zip(
                self.truncated
                    .chunks_mut(l)
                    .zip(self.final_feats.chunks_mut(l * OBS_DIM)),
            )
            .collect();
        let results = self.stepper.map_beside(
            work,
            |((((((slot, a), opp), f), r), d), cut)| {
                step_match(cfg, env, scale, mix, slot, a, opp, f, r, d, cut)
            },
            beside,
        );
        for r in results {
            r?;
        }
        self.ticks += self.env.matches as u64;
        Ok(self
            .slots
            .iter_mut()
            .filter_map(|s| s.finished.take())
            .collect())
    }
}

/// One control tick of one match, with its rows of the batch's buffers;
/// a match that ends restarts with its next episode.
#[allow(clippy::too_many_arguments)]
fn step_match(
    cfg: &MatchConfig,
    env: &EnvConfig,
    scale: &ObsScale,
    mix: &Mix,
    slot: &mut Slot,
    actions: &[usize],
    opp_actions: &[Action],
    feats: &mut [f32],
    rewards: &mut [f32],
    dones: &mut [bool],
    (truncated, final_feats): (&mut [bool], &mut [f32]),
) -> Result<(), LearnError> {
    // A network opponent's actions came from its batched forward pass.
    let opp = mix.kinds[slot.opp].is_none().then_some(opp_actions);
    let done = slot.step(env, &scale.kick, actions, opp, rewards);
    dones.fill(done);
    let cut = done && !slot.game.match_ref().is_finished();
    truncated.fill(cut);
    if cut {
        slot.encode_learners(&env.learners, scale, final_feats);
    }
    if done {
        slot.restart(cfg, env, mix)?;
    }
    slot.encode_learners(&env.learners, scale, feats);
    Ok(())
}

impl Slot {
    /// Draws this episode's opponent and builds fresh built-in policies for
    /// it (they are seeded by the match seed; none where a network plays).
    fn build_policies(&mut self, env: &EnvConfig, mix: &Mix) {
        self.opp = mix.pick(env.seed, self.index, self.episode);
        let opp_kind = mix.kinds[self.opp];
        let team = self.team;
        self.game.build_policies(|r| {
            if r.team() == team {
                (!env.learners.contains(&r.player())).then_some(env.teammates)
            } else {
                opp_kind
            }
        });
    }

    fn encode_learners(&self, learners: &[usize], scale: &ObsScale, out: &mut [f32]) {
        let base = self.team.index() * PLAYERS_PER_TEAM;
        let obs = self.game.observations();
        for (k, &p) in learners.iter().enumerate() {
            scale.encode(&obs[base + p], &mut out[k * OBS_DIM..(k + 1) * OBS_DIM]);
        }
    }

    /// One control tick; returns whether the match ended.
    fn step(
        &mut self,
        env: &EnvConfig,
        reach: &naosoccer_policy::obs::KickReach,
        actions: &[usize],
        opp: Option<&[Action]>,
        rewards: &mut [f32],
    ) -> bool {
        let own = self.team.index() * PLAYERS_PER_TEAM;
        let other = self.team.other().index() * PLAYERS_PER_TEAM;
        // A network's `support` becomes the step toward the robot's support
        // spot, as in play (`LearnedPolicy::action`).
        let field = self.game.match_ref().field();
        let half = [field.half_length, field.half_width];
        let spot = env.support_spot;
        let net = |i: usize| NetAction::from_index(i).expect("a network output is an action");
        for (k, &p) in env.learners.iter().enumerate() {
            let a = to_action(
                net(actions[k]),
                &self.game.observations()[own + p],
                half,
                spot,
                reach,
            );
            self.game.actions_mut()[own + p] = a;
        }
        if let Some(opp) = opp {
            self.game.actions_mut()[other..other + PLAYERS_PER_TEAM].copy_from_slice(opp);
        }
        let score = self.game.match_ref().score();
        // The built-in robots decide, the match steps, a scenario's judge
        // reads the tick and every robot observes.
        let ended = self.game.step().is_some();
        // Each observation carries its robot's reward for the tick
        // (`Match::reward`, what the server sends too).
        for (k, &p) in env.learners.iter().enumerate() {
            let r = self.game.observations()[own + p].reward;
            rewards[k] = r;
            self.returns[k] += r;
        }
        // A scenario match's window: every match starts afresh together
        // at a match's end.
        self.window += 1;
        let window_end = self.scenarios.is_some() && self.window >= self.window_len;
        if window_end {
            self.window = 0;
        }
        let m = self.game.match_ref();
        m.is_finished() || (self.drill.is_some() && m.score() != score) || ended || window_end
    }

    fn restart(&mut self, cfg: &MatchConfig, env: &EnvConfig, mix: &Mix) -> Result<(), LearnError> {
        let m = self.game.match_ref();
        let naosoccer_proto::PerTeam { blue, red } = m.score();
        let (gf, ga) = if self.team == Team::Blue {
            (blue, red)
        } else {
            (red, blue)
        };
        let returns = std::mem::replace(&mut self.returns, vec![0.0; env.learners.len()]);
        self.finished = self.scenarios.is_none().then(|| Episode {
            match_index: self.index,
            learner_team: self.team,
            goals_for: gf,
            goals_against: ga,
            returns,
            stats: m.stats(),
            ticks: m.tick().get(),
        });
        self.episode += 1;
        self.start_episode(cfg, env)?;
        self.build_policies(env, mix);
        self.game.observe_all();
        Ok(())
    }
}
