//! Trained networks as players: [`LearnedPolicy`] implements the client's
//! `Policy` (so the robot client loop plays it over the socket) and the
//! environment's `BatchActor` (so evaluation and self-play run every robot
//! of every match in one forward pass).
//!
//! How a network picks an action ([`ActMode`]): a PPO team samples from its
//! policy distribution (`ppo:DIR`, the trained policy as it was trained) or
//! takes the most likely action (`ppo-greedy:DIR`); a DQN team takes the
//! largest Q-value (`dqn:DIR`) or acts epsilon-greedily with its training
//! run's epsilon (`dqn-epsilon:DIR`). Sampling draws one number per robot and tick
//! from a counter-based hash of (match seed, team, player, tick), so a
//! sampled match is the same in process, over robot connections or over a
//! team connection, whatever the batching.
//!
//! A run directory holds `config.json` (the training configuration, which
//! says how to rebuild the networks) and `final.safetensors` (or, while a run
//! is going, `checkpoints/step-N.safetensors`).

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use naosoccer_client::Policy;
use naosoccer_proto::{Action, Observation, PLAYERS_PER_TEAM};
use tch::nn::VarStore;
use tch::{Kind, Tensor};

use crate::dqn::{argmax, QNet};
use crate::env::BatchActor;
use crate::obs::{layout_dim, ObsScale, OBS_DIM, OBS_VERSION};
use crate::ppo::{rows_tensor, shoot_mask, ActorCritic, DecisionConfig, ACTIONS, SHOOT, STAY};
use crate::train::{Algo, TrainConfig};
use crate::LearnError;

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

/// The uniform number in [0, 1) a sampling robot uses at `tick`: a hash of
/// the match seed, the robot's team and player and the tick, so it does not
/// depend on how robots are batched or in which order they are asked.
pub fn sample_uniform(match_seed: u64, team: usize, player: usize, tick: u64) -> f32 {
    let mut z = match_seed ^ 0x6A09_E667_F3BC_C909;
    for v in [team as u64, player as u64, tick] {
        z = z.wrapping_add(v).wrapping_add(0x9E37_79B9_7F4A_7C15);
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
    }
    (z >> 40) as f32 / (1u64 << 24) as f32
}

/// One robot's decision state in the decision-level MDP (`team` preset):
/// the action it holds and until which tick. The trainer and
/// [`LearnedPolicy`] both use it, so a team decides in play exactly when it
/// decided in training, in process or over the socket.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Hold {
    action: usize,
    until: u64,
    last_tick: Option<u64>,
}

impl Hold {
    /// Whether the robot that received `obs` decides now: it is free to act
    /// (not lying, not busy in a kick) and its last decision's persistence
    /// has run out. A tick earlier than the last one seen is a new match.
    pub fn must_decide(&mut self, obs: &Observation) -> bool {
        if self.last_tick.is_some_and(|t| obs.tick < t) {
            *self = Hold::default();
        }
        self.last_tick = Some(obs.tick);
        is_free(obs) && obs.tick >= self.until
    }

    /// The action of a robot that does not decide now: what it holds while
    /// free, `stay` while lying or kicking (its action is ignored then).
    pub fn held(&self, obs: &Observation) -> usize {
        if is_free(obs) {
            self.action
        } else {
            STAY
        }
    }

    /// Records a decision at `tick`: a movement lasts `persist` ticks, a
    /// `shoot` one (the kick then keeps the robot busy).
    pub fn start(&mut self, action: usize, tick: u64, persist: u32) {
        self.action = action;
        let ticks = if action == SHOOT {
            1
        } else {
            u64::from(persist.max(1))
        };
        self.until = tick + ticks;
    }

    /// Forgets the hold (the episode ended).
    pub fn reset(&mut self) {
        *self = Hold::default();
    }
}

/// Not lying and not in a kick.
pub fn is_free(obs: &Observation) -> bool {
    let me = obs.me();
    !me.fallen && !me.busy
}

/// Feature index of `ball_in_reach` in layout version 2.
const IN_REACH_FEATURE: usize = 12;

enum Model {
    Ppo(ActorCritic),
    /// One network per entry of `learners`, or one shared.
    Dqn(Vec<QNet>),
}

/// A trained team policy.
pub struct LearnedPolicy {
    name: String,
    scale: ObsScale,
    learners: Vec<usize>,
    model: Model,
    mode: ActMode,
    /// Seeds sampling (`ActMode::Sample`); the match seed when playing one match.
    match_seed: u64,
    /// Calls of the unkeyed batch path (training opponents), which key their
    /// samples by this counter instead of a tick.
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
}

impl std::fmt::Debug for LearnedPolicy {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("LearnedPolicy")
            .field("name", &self.name)
            .finish_non_exhaustive()
    }
}

/// Loads `ppo:DIR`, `ppo-greedy:DIR`, `dqn:DIR` (a run directory) or
/// `ppo:FILE.safetensors` (a checkpoint inside a run directory) as a boxed
/// `Policy`, sampling (if it samples) as in a match of seed 0.
pub fn load_policy(spec: &str) -> Result<Box<dyn Policy>, LearnError> {
    load_policy_for_match(spec, 0)
}

/// As [`load_policy`], for a match of seed `match_seed`: the policy the
/// server-side runner and `naosoccer client` build for each match.
pub fn load_policy_for_match(spec: &str, match_seed: u64) -> Result<Box<dyn Policy>, LearnError> {
    let mut p = LearnedPolicy::load(spec)?;
    p.set_match_seed(match_seed);
    Ok(Box::new(p))
}

/// Where a run directory keeps its configuration and weights.
pub fn resolve_run(path: &Path) -> Result<(PathBuf, PathBuf), LearnError> {
    if path.extension().is_some_and(|e| e == "safetensors") {
        // checkpoints/step-N.safetensors -> the run directory two levels up.
        let mut dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
        if !dir.join("config.json").exists() {
            dir = dir.parent().map(Path::to_path_buf).unwrap_or_default();
        }
        return Ok((dir.join("config.json"), path.to_path_buf()));
    }
    let cfg = path.join("config.json");
    let fin = path.join("final.safetensors");
    if fin.exists() {
        return Ok((cfg, fin));
    }
    latest_checkpoint(path)
        .map(|c| (cfg, c))
        .ok_or_else(|| LearnError::Spec {
            spec: path.display().to_string(),
            reason: "no final.safetensors and no checkpoints/step-*.safetensors in it".into(),
        })
}

fn latest_checkpoint(dir: &Path) -> Option<PathBuf> {
    let rd = std::fs::read_dir(dir.join("checkpoints")).ok()?;
    let mut best: Option<(u64, PathBuf)> = None;
    for e in rd.flatten() {
        let p = e.path();
        let Some(n) = p
            .file_name()
            .and_then(|n| n.to_str())
            .and_then(|n| n.strip_prefix("step-"))
            .and_then(|n| n.strip_suffix(".safetensors"))
            .and_then(|n| n.parse::<u64>().ok())
        else {
            continue;
        };
        if best.as_ref().is_none_or(|(b, _)| n > *b) {
            best = Some((n, p));
        }
    }
    best.map(|(_, p)| p)
}

impl LearnedPolicy {
    /// Parses `algo:PATH` and loads it; the algorithm must match the run's.
    pub fn load(spec: &str) -> Result<LearnedPolicy, LearnError> {
        let bad = |reason: &str| LearnError::Spec {
            spec: spec.to_string(),
            reason: reason.to_string(),
        };
        let (kind, path) = spec
            .split_once(':')
            .ok_or_else(|| bad("expected ppo:DIR, ppo-greedy:DIR, dqn:DIR or dqn-epsilon:DIR"))?;
        let algo = match kind {
            "ppo" | "ppo-greedy" => Algo::Ppo,
            "dqn" | "dqn-epsilon" => Algo::Dqn,
            other => {
                return Err(bad(&format!(
                    "unknown kind {other:?} (expected ppo, ppo-greedy, dqn or dqn-epsilon)"
                )))
            }
        };
        let (cfg_path, weights) = resolve_run(Path::new(path))?;
        let text = std::fs::read_to_string(&cfg_path).map_err(|e| LearnError::io(&cfg_path, e))?;
        let cfg: TrainConfig = serde_json::from_str(&text).map_err(|e| LearnError::Json {
            path: cfg_path.clone(),
            source: e,
        })?;
        if cfg.algo != algo {
            return Err(bad(&format!("{} was trained with {}", path, cfg.algo)));
        }
        if layout_dim(cfg.obs_version).is_none() {
            return Err(LearnError::ObsVersion {
                path: cfg_path,
                found: cfg.obs_version,
                expected: OBS_VERSION,
            });
        }
        let mut p = LearnedPolicy::untrained(&cfg, format!("{kind}:{path}"));
        p.mode = match kind {
            "ppo" => ActMode::Sample,
            "dqn-epsilon" => ActMode::EpsilonGreedy {
                epsilon: cfg.dqn.epsilon as f32,
            },
            _ => ActMode::Greedy,
        };
        p.load_weights(&weights)?;
        Ok(p)
    }

    /// The networks `cfg` describes, freshly initialised.
    pub fn untrained(cfg: &TrainConfig, name: String) -> LearnedPolicy {
        let mut scale = cfg.obs_scale;
        scale.version = cfg.obs_version;
        let model = match cfg.algo {
            Algo::Ppo => Model::Ppo(ActorCritic::for_run(&cfg.ppo, &scale, cfg.learners.len())),
            Algo::Dqn => {
                let n = if cfg.dqn.shared {
                    1
                } else {
                    cfg.learners.len()
                };
                Model::Dqn(
                    (0..n)
                        .map(|i| QNet::with_input(scale.dim(), &cfg.dqn.hidden, &format!("q{i}")))
                        .collect(),
                )
            }
        };
        LearnedPolicy {
            name,
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
            decision: match cfg.algo {
                Algo::Ppo => cfg.ppo.decision,
                Algo::Dqn => cfg.dqn.decision,
            },
            holds: BTreeMap::new(),
        }
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
    /// evaluation, self-play): sampling draws from
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
        feats.clear();
        players.clear();
        keys.clear();
        // Rows that decide now: (index into out, hold key, tick).
        let mut deciding: Vec<(usize, (u64, usize, usize), u64)> = Vec::with_capacity(n);
        let mut i = 0;
        for &(seed, obs) in teams {
            for o in obs {
                let key = (seed, o.team.index(), o.player as usize % PLAYERS_PER_TEAM);
                let decides = match self.decision {
                    None => true,
                    Some(_) => {
                        let h = self.holds.entry(key).or_default();
                        let d = h.must_decide(o);
                        if !d {
                            out[i] = h.held(o);
                        }
                        d
                    }
                };
                if decides {
                    let row = feats.len();
                    feats.resize(row + OBS_DIM, 0.0);
                    self.scale.encode(o, &mut feats[row..row + OBS_DIM]);
                    players.push(key.2);
                    keys.push(sample_uniform(seed, key.1, key.2, o.tick));
                    deciding.push((i, key, o.tick));
                }
                i += 1;
            }
        }
        if !deciding.is_empty() {
            let mut acts = vec![0usize; deciding.len()];
            self.act_rows_keyed(&feats, &players, &keys, &mut acts);
            for (&(at, key, tick), &a) in deciding.iter().zip(&acts) {
                out[at] = a;
                if let Some(d) = self.decision {
                    self.holds.entry(key).or_default().start(a, tick, d.persist);
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

    fn stores(&self) -> Vec<&VarStore> {
        match &self.model {
            Model::Ppo(ac) => vec![&ac.vs],
            Model::Dqn(nets) => nets.iter().map(|n| &n.vs).collect(),
        }
    }

    /// Copies the weights of live training networks (self-play snapshots).
    pub fn copy_from(&mut self, src: &[&VarStore]) -> Result<(), LearnError> {
        match &mut self.model {
            Model::Ppo(ac) => ac.vs.copy(src[0])?,
            Model::Dqn(nets) => {
                for (n, s) in nets.iter_mut().zip(src) {
                    n.vs.copy(s)?;
                }
            }
        }
        Ok(())
    }

    pub fn load_weights(&mut self, path: &Path) -> Result<(), LearnError> {
        match &mut self.model {
            Model::Ppo(ac) => ac.vs.load(path)?,
            Model::Dqn(nets) => {
                for n in nets {
                    n.vs.load(path)?;
                }
            }
        }
        Ok(())
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
            keys.extend((0..out.len()).map(|i| sample_uniform(self.match_seed, i, 0, call)));
        }
        self.calls += 1;
        self.act_rows_keyed(obs, players, &keys, out);
        self.keys = keys;
    }

    /// Actions for rows of observation vectors; `players[i]` is the player
    /// number of row `i` and `uniforms[i]` its draw from
    /// [`sample_uniform`] (unused, and may be empty, when greedy).
    pub fn act_rows_keyed(
        &mut self,
        obs: &[f32],
        players: &[usize],
        uniforms: &[f32],
        out: &mut [usize],
    ) {
        self.decide(obs, players, uniforms, out);
        if let ActMode::EpsilonGreedy { epsilon } = self.mode {
            let masks = self.masks_shoot();
            for (i, (a, &u)) in out.iter_mut().zip(uniforms).enumerate() {
                if u < epsilon {
                    // Given u < epsilon, u / epsilon is uniform on [0, 1):
                    // a uniform draw among the actions allowed, which
                    // leaves out a masked `shoot` (ball out of reach).
                    let masked = masks && obs[i * OBS_DIM + IN_REACH_FEATURE] <= 0.5;
                    let allowed = if masked { ACTIONS - 1 } else { ACTIONS };
                    let k = ((u / epsilon * allowed as f32) as usize).min(allowed - 1);
                    *a = if masked && k >= crate::ppo::SHOOT {
                        k + 1
                    } else {
                        k
                    };
                }
            }
        }
    }

    fn decide(&mut self, obs: &[f32], players: &[usize], uniforms: &[f32], out: &mut [usize]) {
        let n = out.len();
        match &self.model {
            Model::Ppo(ac) => {
                let x = ac.actor_input(obs, n);
                let sample = self.mode == ActMode::Sample;
                let mask = self.masks_shoot().then(|| {
                    let ok: Vec<bool> = (0..n)
                        .map(|i| obs[i * OBS_DIM + IN_REACH_FEATURE] > 0.5)
                        .collect();
                    Tensor::from_slice(&shoot_mask(&ok)).view([n as i64, ACTIONS as i64])
                });
                let y = tch::no_grad(|| {
                    let mut logits = ac.logits(&x);
                    if let Some(m) = &mask {
                        logits += m;
                    }
                    if sample {
                        logits.softmax(-1, Kind::Float)
                    } else {
                        logits
                    }
                })
                .to_kind(Kind::Float);
                self.out.resize(n * ACTIONS, 0.0);
                y.copy_data(&mut self.out, n * ACTIONS);
                for (i, o) in out.iter_mut().enumerate() {
                    let row = &self.out[i * ACTIONS..(i + 1) * ACTIONS];
                    *o = if sample {
                        crate::ppo::sample(row, uniforms[i])
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
                    let m = idx.len();
                    let x = rows_tensor(&self.rows, m, OBS_DIM, self.scale.dim());
                    let q = tch::no_grad(|| net.q(&x));
                    self.out.resize(m * ACTIONS, 0.0);
                    q.copy_data(&mut self.out, m * ACTIONS);
                    let masks = self.masks_shoot();
                    for (j, &i) in idx.iter().enumerate() {
                        let row = &mut self.out[j * ACTIONS..(j + 1) * ACTIONS];
                        if masks && obs[i * OBS_DIM + IN_REACH_FEATURE] <= 0.5 {
                            row[SHOOT] = f32::NEG_INFINITY;
                        }
                        out[i] = argmax(row);
                    }
                }
            }
        }
    }

    /// The raw network outputs for `n` rows: PPO's action logits, or DQN's
    /// Q-values (of the network of player `player`), `n * 5` values.
    pub fn outputs(&self, obs: &[f32], player: usize) -> Vec<f32> {
        let n = obs.len() / OBS_DIM;
        let x = rows_tensor(obs, n, OBS_DIM, self.scale.dim());
        let y = tch::no_grad(|| match &self.model {
            Model::Ppo(ac) => ac.logits(&x),
            Model::Dqn(nets) => nets[net_index(&self.learners, nets.len(), player)].q(&x),
        });
        let mut out = vec![0.0; n * ACTIONS];
        y.to_kind(Kind::Float).copy_data(&mut out, n * ACTIONS);
        out
    }

    pub fn scale(&self) -> ObsScale {
        self.scale
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

/// Saves several stores into one safetensors file (their variable names are
/// distinct by construction).
pub fn save_stores(stores: &[&VarStore], path: &Path) -> Result<(), LearnError> {
    let mut named: Vec<(String, Tensor)> = Vec::new();
    for vs in stores {
        let mut vars: Vec<(String, Tensor)> = vs.variables().into_iter().collect();
        // Sorted, so the same weights give the same file bytes.
        vars.sort_by(|a, b| a.0.cmp(&b.0));
        named.extend(vars);
    }
    Tensor::write_safetensors(&named, path)?;
    Ok(())
}

impl LearnedPolicy {
    pub fn save(&self, path: &Path) -> Result<(), LearnError> {
        save_stores(&self.stores(), path)
    }
}

impl Policy for LearnedPolicy {
    fn act(&mut self, obs: &Observation) -> Action {
        let mut out = [0usize];
        let seed = self.match_seed;
        self.act_matches(&[(seed, std::slice::from_ref(obs))], &mut out);
        Action::from_index(out[0]).unwrap_or(Action::Stay)
    }

    fn act_batch(&mut self, obs: &[Observation], out: &mut [Action]) {
        let n = obs.len().min(out.len());
        let mut acts = vec![0usize; n];
        let seed = self.match_seed;
        self.act_matches(&[(seed, &obs[..n])], &mut acts);
        for (o, a) in out.iter_mut().zip(acts) {
            *o = Action::from_index(a).unwrap_or(Action::Stay);
        }
    }

    fn name(&self) -> &str {
        &self.name
    }
}

impl BatchActor for LearnedPolicy {
    fn act_teams(&mut self, teams: &[(u64, &[Observation])], out: &mut [usize]) {
        self.act_matches(teams, out);
    }
}
