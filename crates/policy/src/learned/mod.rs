//! Trained networks as players: [`LearnedPolicy`] implements the client's
//! `Policy` (so the robot client loop plays it over the socket) and plays
//! whole teams of many matches in one call ([`LearnedPolicy::act_matches`],
//! what evaluation and the trainer's opponents use).
//!
//! How a network picks an action ([`ActMode`]): a PPO team samples from its
//! policy distribution (`ppo:DIR`, the trained policy as it was trained) or
//! takes the most likely action (`ppo-greedy:DIR`); a DQN team takes the
//! largest Q-value (`dqn:DIR`) or acts epsilon-greedily with its training
//! run's epsilon (`dqn-epsilon:DIR`). Sampling draws one number per robot and
//! tick from a counter-based hash of (match seed, team, player, tick), so a
//! sampled match is the same in process, over robot connections or over a
//! team connection, whatever the batching (the forward pass, see
//! [`crate::mlp`], does not depend on the batch either).
//!
//! A run directory holds `config.json` (the training configuration, which
//! says how the networks read observations and act) and `final.safetensors`
//! (or, while a run is going, `checkpoints/step-N.safetensors`).
//!
//! This file holds the player; `load.rs` the run's configuration, its
//! files and the specs that name a team.

use std::collections::BTreeMap;
use std::path::Path;

use crate::Policy;
use naosoccer_proto::{Action, Observation, Tick};

use crate::actions::{
    action_count, all_actions, allowed_actions, argmax, argmax_allowed, banned_actions, mask_row,
    nth_allowed, row_bans, sample, sample_uniform, to_action, DecisionConfig, Hold, NetAction,
    SupportSpot,
};
use crate::actions::{ActionSet, MASKED_LOGIT};
use crate::mlp::{Activation, Mlp, Weights};
use crate::obs::{ObsScale, OBS_DIM};
use crate::PolicyError;

mod load;

pub use load::{
    is_learned_spec, load_policy, load_policy_for_match, resolve_run, Algo, DqnPlay, PlayConfig,
    PpoPlay,
};

/// How a trained network turns its outputs into an action.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ActMode {
    /// The largest output (PPO: most likely action; DQN: largest Q-value).
    Greedy,
    /// PPO only: an action drawn from the softmax of the logits.
    Sample,
    /// With probability `epsilon` a uniformly random action, else greedy
    /// (DQN's behaviour policy in training).
    EpsilonGreedy { epsilon: f32 },
}

/// Feature index of `ball_in_reach` in layout version 2.
const IN_REACH_FEATURE: usize = 12;

#[derive(Debug, Clone)]
enum Model {
    /// PPO's actor (the critic plays no part in playing).
    Ppo(Mlp),
    /// One network per entry of `learners`, or one shared.
    Dqn(Vec<Mlp>),
}

/// A trained team policy.
#[derive(Clone)]
pub struct LearnedPolicy {
    name: String,
    cfg: PlayConfig,
    /// The weights the networks were built from (what [`LearnedPolicy::save`] writes).
    weights: Weights,
    scale: ObsScale,
    learners: Vec<usize>,
    model: Model,
    mode: ActMode,
    /// Seeds sampling (`ActMode::Sample`); the match seed when playing one match.
    match_seed: u64,
    /// Calls of the unkeyed batch path ([`LearnedPolicy::act_rows_players`]),
    /// which key their samples by this counter instead of a tick.
    calls: u64,
    feats: Vec<f32>,
    rows: Vec<f32>,
    out: Vec<f32>,
    players: Vec<usize>,
    keys: Vec<f32>,
    /// The decision-level MDP the team was trained in, if any.
    decision: Option<DecisionConfig>,
    /// Per robot (match seed, team, player) decision state.
    holds: BTreeMap<(u64, usize, usize), Hold>,
    /// Outputs per row ([`DecisionConfig::actions`]): 5, or up to 9 for
    /// a team trained with `pass`, `support`, `approach` and `defend`.
    actions: usize,
    /// Per row of the decision in progress: the actions it may not choose
    /// beyond a `shoot` out of reach ([`banned_actions`], filled from the
    /// observations by `act_matches`; a row beyond it cannot pass).
    banned: Vec<ActionSet>,
}

impl std::fmt::Debug for LearnedPolicy {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("LearnedPolicy")
            .field("name", &self.name)
            .finish_non_exhaustive()
    }
}

impl LearnedPolicy {
    /// The networks `cfg` describes with the weights `w` (a checkpoint's, or
    /// the trainer's live networks'), acting greedily until told otherwise.
    pub fn from_weights(
        cfg: &PlayConfig,
        w: &Weights,
        name: String,
    ) -> Result<LearnedPolicy, PolicyError> {
        let scale = cfg.scale();
        let dim = scale.dim();
        let actions = action_count(cfg.decision());
        let check = |m: Mlp, prefix: &str| -> Result<Mlp, PolicyError> {
            if m.input() != dim || m.output() != actions {
                return Err(PolicyError::Weights {
                    name: format!("{prefix}.*"),
                    reason: format!(
                        "a network {} -> {}, expected {dim} -> {actions} (observation layout v{})",
                        m.input(),
                        m.output(),
                        cfg.obs_version
                    ),
                });
            }
            Ok(m)
        };
        let model = match cfg.algo {
            Algo::Ppo => Model::Ppo(check(
                Mlp::from_weights(w, "actor", Activation::Tanh)?,
                "actor",
            )?),
            Algo::Dqn => Model::Dqn(
                (0..cfg.dqn_nets())
                    .map(|i| {
                        let prefix = format!("q{i}");
                        check(Mlp::from_weights(w, &prefix, Activation::Relu)?, &prefix)
                    })
                    .collect::<Result<_, _>>()?,
            ),
        };
        Ok(LearnedPolicy {
            name,
            cfg: cfg.clone(),
            weights: w.clone(),
            scale,
            learners: cfg.learners.clone(),
            model,
            mode: ActMode::Greedy,
            match_seed: 0,
            calls: 0,
            feats: vec![0.0; OBS_DIM],
            rows: Vec::new(),
            out: Vec::new(),
            players: Vec::new(),
            keys: Vec::new(),
            decision: cfg.decision(),
            holds: BTreeMap::new(),
            actions,
            banned: Vec::new(),
        })
    }

    /// Replaces the networks' weights (a self-play snapshot's refresh, or a
    /// checkpoint of the same run); mode, seed and holds are kept.
    pub fn set_weights(&mut self, w: &Weights) -> Result<(), PolicyError> {
        let fresh = LearnedPolicy::from_weights(&self.cfg, w, String::new())?;
        self.model = fresh.model;
        self.weights = fresh.weights;
        Ok(())
    }

    /// [`LearnedPolicy::set_weights`] from a safetensors file.
    pub fn load_weights(&mut self, path: &Path) -> Result<(), PolicyError> {
        self.set_weights(&Weights::read(path)?)
    }

    /// Writes the weights the networks were built from.
    pub fn save(&self, path: &Path) -> Result<(), PolicyError> {
        self.weights.write(path)
    }

    /// The run configuration the team plays by.
    pub fn config(&self) -> &PlayConfig {
        &self.cfg
    }

    /// The decision-level MDP this team plays in (`None`: it decides every tick).
    pub fn decision(&self) -> Option<DecisionConfig> {
        self.decision
    }

    /// Whether `shoot` is masked while the ball is out of reach (read from
    /// the `ball_in_reach` feature of layout version 2).
    fn masks_shoot(&self) -> bool {
        self.decision.is_some_and(|d| d.mask_shoot) && self.scale.version >= 2
    }

    /// Actions for whole teams: `teams[i]` is a match's seed and its team's
    /// observations; `out` gets one action index per observation, in order.
    /// This is how the team plays everywhere (robot and team connections,
    /// evaluation, the trainer's opponents): sampling draws from
    /// [`sample_uniform`]`(match seed, team, player, tick)`, and under the
    /// decision-level MDP each robot (keyed by match seed, team and player)
    /// decides only when free and when its last decision's persistence ran
    /// out, holding its action in between.
    pub fn act_matches(&mut self, teams: &[(u64, &[Observation])], out: &mut [usize]) {
        let n: usize = teams.iter().map(|t| t.1.len()).sum();
        assert!(out.len() >= n, "one action per observation");
        let mut feats = std::mem::take(&mut self.feats);
        let mut players = std::mem::take(&mut self.players);
        let mut keys = std::mem::take(&mut self.keys);
        let mut banned = std::mem::take(&mut self.banned);
        feats.clear();
        players.clear();
        keys.clear();
        banned.clear();
        // Rows that decide now: (index into out, hold key, tick).
        let mut deciding: Vec<(usize, (u64, usize, usize), Tick)> = Vec::with_capacity(n);
        let mut i = 0;
        for &(seed, obs) in teams {
            for o in obs {
                let key = (seed, o.team.index(), o.player.index());
                let decides = match self.decision {
                    None => true,
                    Some(_) => {
                        let h = self.holds.entry(key).or_default();
                        let d = h.must_decide(o);
                        if !d {
                            out[i] = h.held(o).index();
                        }
                        d
                    }
                };
                if decides {
                    let row = feats.len();
                    feats.resize(row + OBS_DIM, 0.0);
                    self.scale.encode(o, &mut feats[row..row + OBS_DIM]);
                    if let Some(d) = &self.decision {
                        banned.push(banned_actions(o, self.scale.kick.in_reach(o), d));
                    }
                    players.push(key.2);
                    keys.push(sample_uniform(seed, key.1, key.2, o.tick));
                    deciding.push((i, key, o.tick));
                }
                i += 1;
            }
        }
        self.banned = banned;
        if !deciding.is_empty() {
            let half = [self.scale.half_length, self.scale.half_width];
            let mut acts = vec![0usize; deciding.len()];
            self.act_rows_banned(&feats, &players, &keys, &mut acts);
            for (&(at, key, tick), &a) in deciding.iter().zip(&acts) {
                out[at] = a;
                if let Some(d) = self.decision {
                    let a = NetAction::from_index(a).expect("a network output is an action");
                    self.holds.entry(key).or_default().start(a, tick, &d, half);
                }
            }
        }
        // Robots of matches no longer played are forgotten now and then.
        if self.holds.len() > 4096 {
            self.holds
                .retain(|k, _| teams.iter().any(|&(seed, _)| seed == k.0));
        }
        self.feats = feats;
        self.players = players;
        self.keys = keys;
    }

    pub fn mode(&self) -> ActMode {
        self.mode
    }

    /// Greedy or sampled actions (sampling needs a PPO network).
    pub fn set_mode(&mut self, mode: ActMode) {
        self.mode = mode;
    }

    /// The seed sampling draws from in `Policy::act`: the match's seed.
    pub fn set_match_seed(&mut self, seed: u64) {
        self.match_seed = seed;
    }

    /// Actions for rows of observation vectors; `players[i]` is the player
    /// number of row `i`. A sampling policy keys its draws by an internal
    /// call counter here (deterministic for a fixed sequence of calls); use
    /// [`LearnedPolicy::act_rows_keyed`] to key them by match and tick.
    pub fn act_rows_players(&mut self, obs: &[f32], players: &[usize], out: &mut [usize]) {
        let mut keys = std::mem::take(&mut self.keys);
        keys.clear();
        if self.mode != ActMode::Greedy {
            let call = self.calls;
            keys.extend(
                (0..out.len()).map(|i| sample_uniform(self.match_seed, i, 0, Tick::new(call))),
            );
        }
        self.calls += 1;
        self.act_rows_keyed(obs, players, &keys, out);
        self.keys = keys;
    }

    /// Actions for rows of observation vectors; `players[i]` is the player
    /// number of row `i` and `uniforms[i]` its draw from
    /// [`sample_uniform`] (unused, and may be empty, when greedy). The rows
    /// carry no observation to find a pass receiver in, so a team trained
    /// with `pass` does not pass here; [`LearnedPolicy::act_matches`] does.
    pub fn act_rows_keyed(
        &mut self,
        obs: &[f32],
        players: &[usize],
        uniforms: &[f32],
        out: &mut [usize],
    ) {
        // Rows carry no bans: none from an earlier `act_matches` either.
        self.banned.clear();
        self.act_rows_banned(obs, players, uniforms, out);
    }

    /// [`LearnedPolicy::act_rows_keyed`] under the bans `self.banned` holds
    /// for these rows (set by [`LearnedPolicy::act_matches`]).
    fn act_rows_banned(
        &mut self,
        obs: &[f32],
        players: &[usize],
        uniforms: &[f32],
        out: &mut [usize],
    ) {
        self.decide(obs, players, uniforms, out);
        if let ActMode::EpsilonGreedy { epsilon } = self.mode {
            for (i, (a, &u)) in out.iter_mut().zip(uniforms).enumerate() {
                if u < epsilon {
                    // Given u < epsilon, u / epsilon is uniform on [0, 1):
                    // a uniform draw among the actions allowed, which
                    // leaves out a masked `shoot` (ball out of reach) and
                    // what the decision settings ban.
                    let allowed = self.allowed(obs, i);
                    let n = (allowed.count_ones() as usize).max(1);
                    let k = ((u / epsilon * n as f32) as usize).min(n - 1);
                    *a = nth_allowed(allowed, k);
                }
            }
        }
    }

    /// The actions row `i` of `obs` may choose: `shoot` per the shoot mask,
    /// the rest per the row's bans ([`row_bans`]); all of them should
    /// nothing be left (as DQN's training draws).
    fn allowed(&self, obs: &[f32], i: usize) -> ActionSet {
        let shoot_ok = !self.masks_shoot() || obs[i * OBS_DIM + IN_REACH_FEATURE] > 0.5;
        let bans = row_bans(&self.banned, i, self.actions);
        match allowed_actions(shoot_ok, bans, self.actions) {
            0 => all_actions(self.actions),
            a => a,
        }
    }

    fn decide(&mut self, obs: &[f32], players: &[usize], uniforms: &[f32], out: &mut [usize]) {
        let n = out.len();
        let masks = self.masks_shoot();
        let shoot_ok = |i: usize| !masks || obs[i * OBS_DIM + IN_REACH_FEATURE] > 0.5;
        let na = self.actions;
        match &self.model {
            Model::Ppo(actor) => {
                actor.forward(obs, n, OBS_DIM, &mut self.out);
                let sample_it = self.mode == ActMode::Sample;
                for (i, o) in out.iter_mut().enumerate() {
                    let row = &mut self.out[i * na..(i + 1) * na];
                    if !shoot_ok(i) {
                        row[NetAction::Shoot.index()] += MASKED_LOGIT;
                    }
                    mask_row(row, row_bans(&self.banned, i, na));
                    *o = if sample_it {
                        softmax(row);
                        sample(row, uniforms[i])
                    } else {
                        argmax(row)
                    };
                }
            }
            Model::Dqn(nets) => {
                for (k, net) in nets.iter().enumerate() {
                    self.rows.clear();
                    let mut idx = Vec::new();
                    for i in 0..n {
                        if net_index(&self.learners, nets.len(), players[i]) == k {
                            idx.push(i);
                            self.rows
                                .extend_from_slice(&obs[i * OBS_DIM..(i + 1) * OBS_DIM]);
                        }
                    }
                    if idx.is_empty() {
                        continue;
                    }
                    net.forward(&self.rows, idx.len(), OBS_DIM, &mut self.out);
                    for (j, &i) in idx.iter().enumerate() {
                        // Greedy over the allowed actions, as in training.
                        let row = &self.out[j * na..(j + 1) * na];
                        let allowed =
                            allowed_actions(shoot_ok(i), row_bans(&self.banned, i, na), na);
                        out[i] = argmax_allowed(row, allowed);
                    }
                }
            }
        }
    }

    /// The raw network outputs for the rows of `obs` (each [`OBS_DIM`]
    /// wide): PPO's action logits, or DQN's Q-values (of the network of
    /// player `player`), `n * actions()` values.
    pub fn outputs(&self, obs: &[f32], player: usize) -> Vec<f32> {
        let n = obs.len() / OBS_DIM;
        let mut out = Vec::new();
        match &self.model {
            Model::Ppo(actor) => actor.forward(obs, n, OBS_DIM, &mut out),
            Model::Dqn(nets) => nets[net_index(&self.learners, nets.len(), player)]
                .forward(obs, n, OBS_DIM, &mut out),
        }
        out
    }

    /// The action probabilities of a PPO team for the rows of `obs`
    /// (softmax of the logits, `shoot` masked as in play), `n * actions()`
    /// values. `pass` is not masked here (the rows carry no observation to
    /// find a receiver in); [`LearnedPolicy::probabilities_for`] masks it.
    pub fn probabilities(&self, obs: &[f32]) -> Vec<f32> {
        self.probabilities_masked(obs, &[])
    }

    /// [`LearnedPolicy::probabilities`] for observations, with every mask
    /// applied as in play (`pass` too).
    pub fn probabilities_for(&self, obs: &[Observation]) -> Vec<f32> {
        let mut feats = vec![0.0; obs.len() * OBS_DIM];
        let mut banned = Vec::with_capacity(obs.len());
        for (o, row) in obs.iter().zip(feats.chunks_exact_mut(OBS_DIM)) {
            self.scale.encode(o, row);
            let in_reach = self.scale.kick.in_reach(o);
            banned.push(self.decision.map_or(0, |d| banned_actions(o, in_reach, &d)));
        }
        self.probabilities_masked(&feats, &banned)
    }

    fn probabilities_masked(&self, obs: &[f32], banned: &[ActionSet]) -> Vec<f32> {
        let mut p = self.outputs(obs, 0);
        let masks = self.masks_shoot();
        for (i, row) in p.chunks_exact_mut(self.actions).enumerate() {
            if masks && obs[i * OBS_DIM + IN_REACH_FEATURE] <= 0.5 {
                row[NetAction::Shoot.index()] += MASKED_LOGIT;
            }
            if !banned.is_empty() {
                mask_row(row, row_bans(banned, i, self.actions));
            }
            softmax(row);
        }
        p
    }

    /// How many actions the team chooses among: 5, 6 with `pass`, 7 with
    /// `support` too, 8 with `approach`.
    pub fn actions(&self) -> usize {
        self.actions
    }

    /// The protocol action that network output `index` (from
    /// [`LearnedPolicy::act_matches`]) stands for in the state `obs`: a
    /// `support` becomes the step toward the robot's support spot
    /// ([`crate::support_action`]), an `approach` the step of
    /// [`crate::approach_action`]; an index past the actions, `stay`.
    pub fn action(&self, index: usize, obs: &Observation) -> Action {
        let Some(a) = NetAction::from_index(index) else {
            return Action::Stay;
        };
        to_action(
            a,
            obs,
            [self.scale.half_length, self.scale.half_width],
            self.decision
                .map_or_else(SupportSpot::default, |d| d.support_spot),
            &self.scale.kick,
        )
    }

    pub fn scale(&self) -> ObsScale {
        self.scale
    }

    pub fn name(&self) -> &str {
        &self.name
    }
}

/// `row` replaced by its softmax: `exp(x - max)` (computed in double
/// precision and rounded), divided by their sum.
pub fn softmax(row: &mut [f32]) {
    let max = row.iter().copied().fold(f32::NEG_INFINITY, f32::max);
    let mut sum = 0.0f32;
    for v in row.iter_mut() {
        *v = f64::from(*v - max).exp() as f32;
        sum += *v;
    }
    for v in row.iter_mut() {
        *v /= sum;
    }
}

/// The DQN network for `player`: per-robot networks follow the training
/// run's `learners` order; a player that did not learn uses the first.
fn net_index(learners: &[usize], nets: usize, player: usize) -> usize {
    if nets <= 1 {
        return 0;
    }
    learners.iter().position(|&p| p == player).unwrap_or(0)
}

impl Policy for LearnedPolicy {
    fn act(&mut self, obs: &Observation) -> Action {
        let mut out = [0usize];
        let seed = self.match_seed;
        self.act_matches(&[(seed, std::slice::from_ref(obs))], &mut out);
        self.action(out[0], obs)
    }

    fn act_batch(&mut self, obs: &[Observation], out: &mut [Action]) {
        let n = obs.len().min(out.len());
        let mut acts = vec![0usize; n];
        let seed = self.match_seed;
        self.act_matches(&[(seed, &obs[..n])], &mut acts);
        for ((o, a), ob) in out.iter_mut().zip(acts).zip(obs) {
            *o = self.action(a, ob);
        }
    }

    fn name(&self) -> &str {
        &self.name
    }
}
