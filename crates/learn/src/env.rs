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
//! its index and its episode number.

use naosoccer_client::{Policy, PolicyKind};
use naosoccer_proto::{Action, Observation, RobotId, Team, PLAYERS_PER_TEAM, ROBOTS};
use naosoccer_referee::rules::segment_distance;
use naosoccer_referee::{Match, MatchConfig};

use crate::obs::{ObsScale, OBS_DIM};
use crate::LearnError;
pub use naosoccer_policy::BatchActor;
use naosoccer_policy::{to_action, SupportSpot};

/// Who plays against the learner.
pub enum Opponent {
    /// A built-in policy, one instance per robot.
    Builtin(PolicyKind),
    /// A network (frozen checkpoint or self-play snapshot), batched over all
    /// matches.
    Net(Box<dyn BatchActor>),
}

impl Opponent {
    fn builtin_kind(&self) -> Option<PolicyKind> {
        match self {
            Opponent::Builtin(k) => Some(*k),
            Opponent::Net(_) => None,
        }
    }
}

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
    m: Match,
    team: Team,
    episode: u64,
    /// Observations of all eight robots, by robot index.
    obs: Vec<Observation>,
    /// Built-in policies by robot index (none where a network decides).
    policies: Vec<Option<Box<dyn Policy>>>,
    returns: Vec<f32>,
    finished: Option<Episode>,
    /// Index of this episode's opponent.
    opp: usize,
    drill: Option<Drill>,
    /// This match plays these pass drills.
    pass_drill: Option<PassDrills>,
}

/// Pass drills mixed into a run's matches: the last `matches` of the
/// matches played side by side (with an even number, as many as blue as as
/// red) play episodes of `ticks` control ticks, each staged as a pass.
///
/// In the learner's frame (attacking +x): the ball at a random spot
/// (x in -2..1.5, |y| <= 1.6), a learning robot 0.2 m behind it with the
/// ball straight ahead, facing within 60 degrees of the opponent goal;
/// a teammate 1.2-2.5 m further on, within `angle` of the kicker's heading
/// (0.15 rad, 9 degrees, by default: in its line) and ahead of the ball
/// (toward the opponent goal, so that a pass to it is paid), facing the
/// ball; the other teammates anywhere in the
/// field at least 1 m from the ball; the opponent keeper before its goal
/// and the other opponents at least 1.2 m from the ball and 0.5 m from the
/// line from ball to receiver, facing the ball. The match then plays on
/// as any match, against the episode's opponent from the run's mix.
///
/// A drill episode is cut after `ticks` ticks as a rollout's edge cuts one:
/// its last transition is bootstrapped with the critic's value of the state
/// reached, since the match would go on (the observation's clock says so).
/// `ticks` must divide a match's length, so that every match still ends
/// together at a match's end (a checkpoint's boundary). Drill episodes are
/// not reported among finished episodes (goals, returns).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct PassDrills {
    pub matches: usize,
    pub ticks: u64,
    /// The receiver's largest angle off the kicker's heading, radians:
    /// small, it stands in the kicker's line; wide, the kicker must turn
    /// with the ball to pass.
    #[serde(default = "PassDrills::default_angle")]
    pub angle: f32,
}

impl PassDrills {
    /// Distance from the kicker's torso to the ball's centre at the start.
    pub const KICKER_DISTANCE: f32 = 0.2;
    /// The receiver's distance from the ball, metres.
    pub const RECEIVER: (f32, f32) = (1.2, 2.5);
    /// The receiver's largest angle off the kicker's heading by default,
    /// radians.
    pub const LANE_ANGLE: f32 = 0.15;

    fn default_angle() -> f32 {
        Self::LANE_ANGLE
    }
    /// The kicker's largest heading off +x, radians (60 degrees).
    pub const HEADING: f32 = std::f32::consts::FRAC_PI_3;
}

/// A drill instead of a match: the learning robots alone before the
/// opponent goal (every other robot stands aside, by the own goal line),
/// the ball at a random spot of the attacking half and each learner within
/// `robot_radius` of it, facing anywhere. The episode ends with a goal (a
/// success) or when the match clock runs out; it is played in one half.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Drill {
    /// Ball x range (metres, the learner's frame: attacking +x).
    pub ball_x: (f32, f32),
    /// Ball |y| bound, metres.
    pub ball_y: f32,
    /// Largest robot-ball distance at the start, metres (at least 0.25).
    pub robot_radius: f32,
    /// The learner stands at an angle in +-`spread` (radians) from the
    /// spot straight behind the ball (on the side away from the goal):
    /// pi puts it anywhere around the ball.
    pub spread: f32,
    /// It faces the ball turned by up to +-this (radians): pi, anywhere.
    pub heading_noise: f32,
}

impl Default for Drill {
    /// Anywhere around the ball, facing anywhere.
    fn default() -> Drill {
        Drill {
            ball_x: (0.5, 2.0),
            ball_y: 1.2,
            robot_radius: 0.8,
            spread: std::f32::consts::PI,
            heading_noise: std::f32::consts::PI,
        }
    }
}

impl Drill {
    /// The easier drill of the learning test: behind the ball (within 45
    /// degrees of straight behind it), roughly facing it (+-30 degrees).
    pub fn behind_the_ball() -> Drill {
        Drill {
            ball_x: (0.5, 2.0),
            ball_y: 1.0,
            robot_radius: 0.6,
            spread: std::f32::consts::FRAC_PI_4,
            heading_noise: std::f32::consts::FRAC_PI_6,
        }
    }
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
    /// Rows whose episode was cut (a pass drill's end) with the last step.
    truncated: Vec<bool>,
    /// Those rows' observation vectors at the cut (before the restart).
    final_feats: Vec<f32>,
    opp_actions: Vec<usize>,
    ticks: u64,
}

/// How each episode picks its opponent: by weight, from a hash of the run's
/// seed, the match index and the episode (so the choice does not depend on
/// threads or on when it is asked).
#[derive(Debug, Clone)]
struct Mix {
    kinds: Vec<Option<PolicyKind>>,
    /// Cumulative weights, normalised to end at 1.
    cumulative: Vec<f64>,
}

impl Mix {
    fn new(opponents: &[Opponent], weights: &[f64]) -> Result<Mix, LearnError> {
        let total: f64 = weights.iter().sum();
        if opponents.is_empty()
            || opponents.len() != weights.len()
            || weights.iter().any(|w| !w.is_finite() || *w < 0.0)
            || !total.is_finite()
            || total <= 0.0
        {
            return Err(LearnError::Config(format!(
                "opponent weights {weights:?} for {} opponents",
                opponents.len()
            )));
        }
        let mut acc = 0.0;
        Ok(Mix {
            kinds: opponents.iter().map(Opponent::builtin_kind).collect(),
            cumulative: weights
                .iter()
                .map(|w| {
                    acc += w / total;
                    acc
                })
                .collect(),
        })
    }

    fn pick(&self, seed: u64, index: usize, episode: u64) -> usize {
        let u = (episode_seed(seed ^ 0x5EED_0FF0_0000_0001, index, episode) >> 11) as f64
            / (1u64 << 53) as f64;
        self.cumulative
            .iter()
            .position(|&c| u < c)
            .unwrap_or(self.cumulative.len() - 1)
    }
}

pub use naosoccer_policy::eval::{episode_seed, legacy_episode_seed};

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
            let m = Match::new(cfg, episode_seed(env.seed, index, 0))?;
            let mut slot = Slot {
                index,
                obs: (0..ROBOTS)
                    .map(|_| naosoccer_referee::blank_observation())
                    .collect(),
                policies: Vec::new(),
                returns: vec![0.0; l],
                m,
                team,
                episode: 0,
                finished: None,
                opp: 0,
                drill: None,
                pass_drill: None,
            };
            slot.build_policies(&env, &mix);
            slot.observe_all();
            slots.push(slot);
        }
        let scale = ObsScale::from_config(cfg);
        let mut venv = VecEnv {
            cfg: cfg.clone(),
            feats: vec![0.0; env.matches * l * OBS_DIM],
            rewards: vec![0.0; env.matches * l],
            dones: vec![false; env.matches * l],
            truncated: vec![false; env.matches * l],
            final_feats: vec![0.0; env.matches * l * OBS_DIM],
            opp_actions: Vec::new(),
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
    /// pass drill's end, [`PassDrills`]) rather than by the match's end:
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
        &slot.obs[slot.team.index() * PLAYERS_PER_TEAM + self.env.learners[row % l]]
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

    /// Plays `drill` episodes instead of matches (`None`: matches); every
    /// match starts its current episode afresh. A drill is played in one
    /// half (a half-time kick-off would put everything back in place).
    pub fn set_drill(&mut self, drill: Option<Drill>) -> Result<(), LearnError> {
        if drill.is_some() {
            self.cfg.rules.halves = 1;
        }
        for slot in &mut self.slots {
            slot.drill = drill;
        }
        let episodes = self.episodes();
        self.restart_at(&episodes, self.ticks)
    }

    /// Plays pass drills in the last `drills.matches` matches (`None`: none);
    /// every match starts its current episode afresh. See [`PassDrills`].
    pub fn set_pass_drills(&mut self, drills: Option<PassDrills>) -> Result<(), LearnError> {
        if let Some(d) = drills {
            let total = self.slots[0].m.total_ticks();
            if d.matches == 0 || d.matches > self.slots.len() {
                return Err(LearnError::Config(format!(
                    "pass drills in {} matches: between 1 and the {} matches played",
                    d.matches,
                    self.slots.len()
                )));
            }
            if d.ticks == 0 || !total.is_multiple_of(d.ticks) {
                return Err(LearnError::Config(format!(
                    "a pass drill of {} ticks must divide the match's {total} ticks",
                    d.ticks
                )));
            }
            if !(0.0..=std::f32::consts::FRAC_PI_2).contains(&d.angle) {
                return Err(LearnError::Config(format!(
                    "a pass drill's receiver angle of {} rad: between 0 and pi/2",
                    d.angle
                )));
            }
            if self.slots.iter().any(|s| s.drill.is_some()) {
                return Err(LearnError::Config(
                    "pass drills mix into matches, not into drills".into(),
                ));
            }
        }
        let n = self.slots.len();
        for (i, slot) in self.slots.iter_mut().enumerate() {
            slot.pass_drill = drills.filter(|d| i >= n - d.matches);
        }
        let episodes = self.episodes();
        self.restart_at(&episodes, self.ticks)
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
            slot.m = Match::new(&self.cfg, episode_seed(self.env.seed, slot.index, e))?;
            slot.place_drill(&self.env);
            slot.place_pass_drill(&self.env);
            slot.returns = vec![0.0; l];
            slot.finished = None;
            slot.build_policies(&self.env, &self.mix);
            slot.observe_all();
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
        let l = self.env.learners.len();
        assert_eq!(actions.len(), self.rows(), "one action per learning robot");
        self.opp_actions
            .resize(self.env.matches * PLAYERS_PER_TEAM, 0);
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
                teams.push((slot.m.seed(), &slot.obs[base..base + PLAYERS_PER_TEAM]));
                at.push(j);
            }
            if teams.is_empty() {
                continue;
            }
            acts.resize(teams.len() * PLAYERS_PER_TEAM, 0);
            actor.act_teams(&teams, &mut acts);
            for (i, &j) in at.iter().enumerate() {
                self.opp_actions[j * PLAYERS_PER_TEAM..(j + 1) * PLAYERS_PER_TEAM]
                    .copy_from_slice(&acts[i * PLAYERS_PER_TEAM..(i + 1) * PLAYERS_PER_TEAM]);
            }
        }
        let threads = self.env.threads.clamp(1, self.env.matches);
        let per = self.env.matches.div_ceil(threads);
        let cfg = &self.cfg;
        let env = &self.env;
        let scale = &self.scale;
        let mix = &self.mix;
        let opp_actions: &[usize] = &self.opp_actions;
        let work = self
            .slots
            .chunks_mut(per)
            .zip(actions.chunks(per * l))
            .zip(self.feats.chunks_mut(per * l * OBS_DIM))
            .zip(self.rewards.chunks_mut(per * l))
            .zip(self.dones.chunks_mut(per * l))
            .zip(
                self.truncated
                    .chunks_mut(per * l)
                    .zip(self.final_feats.chunks_mut(per * l * OBS_DIM)),
            )
            .enumerate();
        let results: Vec<Result<(), LearnError>> = if threads == 1 {
            work.map(|(c, (((((slots, a), f), r), d), cut))| {
                step_chunk(
                    cfg,
                    env,
                    scale,
                    mix,
                    slots,
                    a,
                    opp_chunk(opp_actions, c, per),
                    f,
                    r,
                    d,
                    cut,
                )
            })
            .collect()
        } else {
            std::thread::scope(|s| {
                let handles: Vec<_> = work
                    .map(|(c, (((((slots, a), f), r), d), cut))| {
                        let opp = opp_chunk(opp_actions, c, per);
                        s.spawn(move || {
                            step_chunk(cfg, env, scale, mix, slots, a, opp, f, r, d, cut)
                        })
                    })
                    .collect();
                handles
                    .into_iter()
                    .map(|h| h.join().unwrap_or_else(|e| std::panic::resume_unwind(e)))
                    .collect()
            })
        };
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

fn opp_chunk(opp: &[usize], chunk: usize, per: usize) -> &[usize] {
    let n = per * PLAYERS_PER_TEAM;
    let start = (chunk * n).min(opp.len());
    &opp[start..(start + n).min(opp.len())]
}

#[allow(clippy::too_many_arguments)]
fn step_chunk(
    cfg: &MatchConfig,
    env: &EnvConfig,
    scale: &ObsScale,
    mix: &Mix,
    slots: &mut [Slot],
    actions: &[usize],
    opp_actions: &[usize],
    feats: &mut [f32],
    rewards: &mut [f32],
    dones: &mut [bool],
    (truncated, final_feats): (&mut [bool], &mut [f32]),
) -> Result<(), LearnError> {
    let l = env.learners.len();
    for (j, slot) in slots.iter_mut().enumerate() {
        // A network opponent's actions came from its batched forward pass.
        let opp = mix.kinds[slot.opp]
            .is_none()
            .then(|| &opp_actions[j * PLAYERS_PER_TEAM..(j + 1) * PLAYERS_PER_TEAM]);
        let done = slot.step(
            env,
            &actions[j * l..(j + 1) * l],
            opp,
            &mut rewards[j * l..(j + 1) * l],
        );
        dones[j * l..(j + 1) * l].fill(done);
        let cut = done && !slot.m.is_finished();
        truncated[j * l..(j + 1) * l].fill(cut);
        if cut {
            slot.encode_learners(
                &env.learners,
                scale,
                &mut final_feats[j * l * OBS_DIM..(j + 1) * l * OBS_DIM],
            );
        }
        if done {
            slot.restart(cfg, env, mix)?;
        }
        slot.encode_learners(
            &env.learners,
            scale,
            &mut feats[j * l * OBS_DIM..(j + 1) * l * OBS_DIM],
        );
    }
    Ok(())
}

impl Slot {
    /// Draws this episode's opponent and builds fresh built-in policies for
    /// it (they are seeded by the match seed; none where a network plays).
    fn build_policies(&mut self, env: &EnvConfig, mix: &Mix) {
        self.opp = mix.pick(env.seed, self.index, self.episode);
        let opp_kind = mix.kinds[self.opp];
        let seed = self.m.seed();
        self.policies = RobotId::all()
            .map(|r| {
                if r.team() == self.team {
                    (!env.learners.contains(&r.player())).then(|| env.teammates.build(seed, r))
                } else {
                    opp_kind.map(|k| k.build(seed, r))
                }
            })
            .collect();
    }

    fn observe_all(&mut self) {
        for r in RobotId::all() {
            self.m
                .observe_into(r.team(), r.player(), &mut self.obs[r.index()]);
        }
    }

    fn encode_learners(&self, learners: &[usize], scale: &ObsScale, out: &mut [f32]) {
        let base = self.team.index() * PLAYERS_PER_TEAM;
        for (k, &p) in learners.iter().enumerate() {
            scale.encode(
                &self.obs[base + p],
                &mut out[k * OBS_DIM..(k + 1) * OBS_DIM],
            );
        }
    }

    /// One control tick; returns whether the match ended.
    fn step(
        &mut self,
        env: &EnvConfig,
        actions: &[usize],
        opp: Option<&[usize]>,
        rewards: &mut [f32],
    ) -> bool {
        let mut joint = [Action::Stay; ROBOTS];
        let own = self.team.index() * PLAYERS_PER_TEAM;
        let other = self.team.other().index() * PLAYERS_PER_TEAM;
        // A network's `support` becomes the step toward the robot's support
        // spot, as in play (`LearnedPolicy::action`).
        let field = self.m.field();
        let half = [field.half_length, field.half_width];
        let spot = env.support_spot;
        for (k, &p) in env.learners.iter().enumerate() {
            joint[own + p] = to_action(actions[k], &self.obs[own + p], half, spot);
        }
        if let Some(opp) = opp {
            for p in 0..PLAYERS_PER_TEAM {
                joint[other + p] = to_action(opp[p], &self.obs[other + p], half, spot);
            }
        }
        for (i, policy) in self.policies.iter_mut().enumerate() {
            if let Some(policy) = policy {
                joint[i] = policy.act(&self.obs[i]);
            }
        }
        let score = self.m.score();
        self.m.step(&joint);
        self.observe_all();
        // Each observation carries its robot's reward for the tick
        // (`Match::reward`, what the server sends too).
        for (k, &p) in env.learners.iter().enumerate() {
            let r = self.obs[own + p].reward;
            rewards[k] = r;
            self.returns[k] += r;
        }
        self.m.is_finished()
            || (self.drill.is_some() && self.m.score() != score)
            || self
                .pass_drill
                .is_some_and(|d| self.m.tick().get() >= d.ticks)
    }

    fn restart(&mut self, cfg: &MatchConfig, env: &EnvConfig, mix: &Mix) -> Result<(), LearnError> {
        let naosoccer_proto::PerTeam { blue, red } = self.m.score();
        let (gf, ga) = if self.team == Team::Blue {
            (blue, red)
        } else {
            (red, blue)
        };
        let returns = std::mem::replace(&mut self.returns, vec![0.0; env.learners.len()]);
        self.finished = self.pass_drill.is_none().then(|| Episode {
            match_index: self.index,
            learner_team: self.team,
            goals_for: gf,
            goals_against: ga,
            returns,
            stats: self.m.stats(),
            ticks: self.m.tick().get(),
        });
        self.episode += 1;
        self.m = Match::new(cfg, episode_seed(env.seed, self.index, self.episode))?;
        self.place_drill(env);
        self.place_pass_drill(env);
        self.build_policies(env, mix);
        self.observe_all();
        Ok(())
    }

    /// A generator for placing this episode, seeded by the run's seed
    /// (mixed with `salt`), the match and the episode.
    fn episode_rng(&self, env: &EnvConfig, salt: u64) -> rand_chacha::ChaCha8Rng {
        use rand::SeedableRng;
        rand_chacha::ChaCha8Rng::seed_from_u64(episode_seed(
            env.seed ^ salt,
            self.index,
            self.episode,
        ))
    }

    /// The learner's frame to the world's: the sign of x and y and the
    /// turn added to a heading (red sees the world turned half round).
    fn to_world(&self) -> (f32, f32) {
        if self.team == Team::Blue {
            (1.0, 0.0)
        } else {
            (-1.0, std::f32::consts::PI)
        }
    }

    /// Stages a pass drill episode (see [`PassDrills`]), placed from the
    /// episode's seed.
    fn place_pass_drill(&mut self, env: &EnvConfig) {
        let Some(drill) = self.pass_drill else {
            return;
        };
        use rand::Rng;
        let mut rng = self.episode_rng(env, 0x9A55_D111_1D00);
        let half_x = self.m.config().sim.field_length * 0.5;
        let half_y = self.m.config().sim.field_width * 0.5;
        // Kicker and receiver: two own players, learners first.
        let mut own: Vec<usize> = (0..PLAYERS_PER_TEAM).collect();
        own.sort_by_key(|p| !env.learners.contains(p));
        let learners = env.learners.len().max(1);
        let kicker = own[rng.random_range(0..learners)];
        own.retain(|&p| p != kicker);
        let receiver = own.remove(rng.random_range(0..own.len().min(learners.max(2) - 1)));
        // Ball, kicker heading and receiver, drawn until the receiver stands
        // inside the field (0.3 m from the lines).
        let (mut ball, mut heading, mut recv) = ((0.0, 0.0), 0.0f32, (0.0, 0.0, 0.0));
        for _ in 0..32 {
            ball = (
                rng.random_range(-2.0..=1.5f32),
                rng.random_range(-1.6..=1.6f32),
            );
            heading = rng.random_range(-PassDrills::HEADING..=PassDrills::HEADING);
            let d = rng.random_range(PassDrills::RECEIVER.0..=PassDrills::RECEIVER.1);
            let a = heading + rng.random_range(-drill.angle..=drill.angle);
            let (x, y) = (ball.0 + d * a.cos(), ball.1 + d * a.sin());
            recv = (x, y, a + std::f32::consts::PI);
            if x.abs() <= half_x - 0.3 && y.abs() <= half_y - 0.3 && x - ball.0 >= 0.3 {
                break;
            }
        }
        recv.0 = recv.0.clamp(-half_x + 0.3, half_x - 0.3);
        recv.1 = recv.1.clamp(-half_y + 0.3, half_y - 0.3);
        let k = PassDrills::KICKER_DISTANCE;
        let mut spots = [(0.0f32, 0.0f32, 0.0f32); ROBOTS];
        let base = self.team.index() * PLAYERS_PER_TEAM;
        let foe = self.team.other().index() * PLAYERS_PER_TEAM;
        spots[base + kicker] = (
            ball.0 - k * heading.cos(),
            ball.1 - k * heading.sin(),
            heading,
        );
        spots[base + receiver] = recv;
        let facing = |x: f32, y: f32| (ball.1 - y).atan2(ball.0 - x);
        // A spot at least `min` from the ball (and `lane` from the line ball
        // to receiver), drawn in the x range given.
        let draw = |rng: &mut rand_chacha::ChaCha8Rng, xs: (f32, f32), min: f32, lane: f32| {
            let mut p = (0.0, 0.0);
            for _ in 0..32 {
                p = (
                    rng.random_range(xs.0..=xs.1),
                    rng.random_range(-(half_y - 0.45)..=(half_y - 0.45)),
                );
                let far = (p.0 - ball.0).hypot(p.1 - ball.1) >= min;
                if far && segment_distance([ball.0, ball.1], [recv.0, recv.1], [p.0, p.1]) >= lane {
                    break;
                }
            }
            (p.0, p.1, facing(p.0, p.1))
        };
        for &p in &own {
            spots[base + p] = draw(&mut rng, (-(half_x - 0.4), half_x - 0.4), 1.0, 0.0);
        }
        spots[foe] = (
            half_x - 0.4,
            rng.random_range(-0.5..=0.5f32),
            std::f32::consts::PI,
        );
        for p in 1..PLAYERS_PER_TEAM {
            spots[foe + p] = draw(&mut rng, (-2.0, half_x - 0.4), 1.2, 0.5);
        }
        let (sign, turn) = self.to_world();
        let world = spots.map(|(x, y, h)| (sign * x, sign * y, h + turn));
        self.m
            .sim_mut()
            .place_all((sign * ball.0, sign * ball.1), &world);
        self.m.clear_set_play();
    }

    /// Sets up a drill episode (see [`Drill`]), placed from the episode's
    /// seed.
    fn place_drill(&mut self, env: &EnvConfig) {
        let Some(d) = self.drill else {
            return;
        };
        use rand::Rng;
        let mut rng = self.episode_rng(env, 0xD1_11D1_11D1);
        let (sign, turn) = self.to_world();
        let bx = rng.random_range(d.ball_x.0..=d.ball_x.1);
        let by = rng.random_range(-d.ball_y..=d.ball_y);
        let sim = self.m.sim_mut();
        sim.place_ball(sign * bx, sign * by);
        let own = self.team.index() * PLAYERS_PER_TEAM;
        let mut aside = 0;
        for r in RobotId::all() {
            let i = r.index();
            let learner =
                i >= own && i < own + PLAYERS_PER_TEAM && env.learners.contains(&(i - own));
            if learner {
                let dist = rng.random_range(0.25..=d.robot_radius.max(0.25));
                let ang = rng.random_range(-d.spread..=d.spread);
                let noise = rng.random_range(-d.heading_noise..=d.heading_noise);
                // Straight behind the ball is -x from it; the robot faces
                // the ball, turned by the noise.
                let (x, y) = (bx - dist * ang.cos(), by - dist * ang.sin());
                let h = ang + noise;
                sim.place_robot(i, sign * x, sign * y, h + turn);
            } else {
                let (x, y) = (-2.6, -2.0 + 0.55 * aside as f32);
                sim.place_robot(i, sign * x, sign * y, turn);
                aside += 1;
            }
        }
        // A staged ball, not a kick-off: nobody is held back from it, and
        // the kick-off rule does not disallow the drill's goal.
        self.m.clear_set_play();
    }
}
