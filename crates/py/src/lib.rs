//! `naosoccer._native`: the Python extension module. It moves numpy arrays
//! in and out of [`vector::VecMatches`] and releases the GIL while the
//! matches step; the Gymnasium conventions (spaces, infos, auto-reset
//! bookkeeping) are in `python/naosoccer/vector.py`, the PettingZoo ones
//! (one match, agents, episodes that end) in `python/naosoccer/parallel.py`.
//! Frames for `render()` are drawn by `naosoccer render`'s own code
//! (crates/render).

pub mod state;
pub mod vector;

use std::sync::{Mutex, MutexGuard};

use numpy::{PyArray1, PyArrayMethods, PyReadonlyArray1, PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

use naosoccer_policy::export::{write_ppo_team, Layer};
use naosoccer_policy::DecisionConfig;
use naosoccer_record::StateRecord;
use naosoccer_referee::{MatchConfig, Scenario};
use vector::{Controlled, EnvSpec, Finished, StepOut, VecEnvError, VecMatches};

fn value_error(e: impl std::fmt::Display) -> PyErr {
    PyValueError::new_err(e.to_string())
}

impl From<VecEnvError> for PyErr {
    fn from(e: VecEnvError) -> PyErr {
        match e {
            // Not the caller's mistake: a bug, or the machine.
            VecEnvError::Panicked(_) | VecEnvError::Thread(_) => {
                PyRuntimeError::new_err(e.to_string())
            }
            e => value_error(e),
        }
    }
}

/// N matches stepped in process, one control tick a step.
///
/// `VecMatches(num_matches, team, opponent, obs_version, decision_json,
/// config_toml, minutes, threads, scenario_toml, restart=True,
/// scenario_weights=None)`; see `naosoccer.VectorEnv` and
/// `naosoccer.parallel_env`, which wrap it. `scenario_toml`: one scenario's
/// text, or a list of them, each match start drawing one from its seed
/// with chances in proportion to `scenario_weights` (default equal).
/// `opponent` `None`: the one the scenarios name, each scenario's own when
/// they name different built-in policies (`opponent` is then `"per
/// scenario"`), `scripted` without a scenario. `restart=False`: a finished
/// match stays until the next `reset`.
/// `close()` stops the stepping threads and frees the matches.
#[pyclass(module = "naosoccer._native", name = "VecMatches")]
struct VecMatchesPy {
    // Locked only by the thread that holds the Python object's borrow; the
    // mutex makes the class shareable between Python threads. `None` once
    // closed.
    inner: Mutex<Option<VecMatches>>,
    shape: (usize, usize, usize, usize),
    opponent: Option<String>,
    control_hz: f32,
}

/// `scenario_toml`: one scenario's text or a list of them.
#[derive(FromPyObject)]
enum ScenarioTexts {
    One(String),
    Many(Vec<String>),
}

#[pymethods]
impl VecMatchesPy {
    #[new]
    #[pyo3(signature = (num_matches, team, opponent, obs_version, decision_json=None, config_toml=None, minutes=None, threads=1, scenario_toml=None, restart=true, scenario_weights=None))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        num_matches: usize,
        team: &str,
        opponent: Option<&str>,
        obs_version: u32,
        decision_json: Option<&str>,
        config_toml: Option<&str>,
        minutes: Option<f32>,
        threads: usize,
        scenario_toml: Option<ScenarioTexts>,
        restart: bool,
        scenario_weights: Option<Vec<f64>>,
    ) -> PyResult<Self> {
        let mut config = match config_toml {
            Some(t) => MatchConfig::from_toml_str(t).map_err(value_error)?,
            None => MatchConfig::default(),
        };
        if let Some(m) = minutes {
            config.minutes = m;
        }
        let decision = match decision_json {
            Some(j) => Some(
                serde_json::from_str::<DecisionConfig>(j)
                    .map_err(|e| value_error(format!("decision: {e}")))?,
            ),
            None => None,
        };
        let scenarios = match scenario_toml {
            None => Vec::new(),
            Some(ScenarioTexts::One(t)) => {
                vec![Scenario::from_toml(&t, None).map_err(value_error)?]
            }
            Some(ScenarioTexts::Many(texts)) if texts.is_empty() => {
                return Err(value_error(
                    "scenario: an empty list: give at least one scenario",
                ))
            }
            // With two or more, an error names the entry by its place (a
            // text that does not parse has no name yet).
            Some(ScenarioTexts::Many(texts)) => texts
                .iter()
                .enumerate()
                .map(|(i, t)| {
                    Scenario::from_toml(t, None).map_err(|e| match texts.len() {
                        1 => value_error(e),
                        _ => value_error(format!("scenario[{i}]: {e}")),
                    })
                })
                .collect::<PyResult<_>>()?,
        };
        let control_hz = config.control_hz;
        // As `naosoccer match --scenario`: the files' opponents unless
        // named (VecMatches::opponent).
        let env = VecMatches::new(EnvSpec {
            matches: num_matches,
            controlled: Controlled::parse(team)?,
            opponent: opponent.map(str::to_owned),
            config,
            obs_version,
            decision,
            threads,
            scenarios,
            scenario_weights,
            restart,
        })?;
        let opponent = env.opponent().map(str::to_owned);
        let shape = (
            env.num_matches(),
            env.robots(),
            env.obs_dim(),
            env.actions(),
        );
        Ok(VecMatchesPy {
            inner: Mutex::new(Some(env)),
            shape,
            opponent,
            control_hz,
        })
    }

    /// The opponents' policy spec, as resolved (`opponent`, else the one
    /// the scenarios name, else `"per scenario"`: each match its own
    /// scenario's; `scripted` without a scenario; `None` with `team="both"`).
    #[getter]
    fn opponent(&self) -> Option<&str> {
        self.opponent.as_deref()
    }

    /// (matches, robots per match, observation length, actions).
    #[getter]
    fn shape(&self) -> (usize, usize, usize, usize) {
        self.shape
    }

    /// Control ticks a second of game time (one `step` is one tick).
    #[getter]
    fn control_hz(&self) -> f32 {
        self.control_hz
    }

    /// Threads stepping the matches, the caller's included.
    #[getter]
    fn threads(&self) -> PyResult<usize> {
        Ok(open(&mut lock(&self.inner))?.threads())
    }

    /// Stops the stepping threads (waiting for them) and frees the matches;
    /// every later call but `close` raises `RuntimeError`.
    fn close(&self, py: Python<'_>) {
        let inner = &self.inner;
        // Dropped outside the lock; the workers need no GIL to stop.
        let env = lock(inner).take();
        py.detach(move || drop(env));
    }

    /// Each slot's global state: float32 `(matches, STATE_DIM)`, entries
    /// named by `STATE_NAMES` (world frame, both teams).
    fn state<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let mut out = Vec::new();
        open(&mut lock(&self.inner))?.write_states(&mut out);
        let n = out.len() / state::STATE_DIM;
        Ok(PyArray1::from_vec(py, out)
            .reshape([n, state::STATE_DIM])?
            .into_any())
    }

    /// Slot `slot`'s current match drawn as `naosoccer render --gif` draws
    /// each frame: uint8 `(height, width, 3)`, `width` pixels wide (120 to
    /// 4000), the height following the pitch.
    fn render<'py>(&self, py: Python<'py>, slot: usize, width: u32) -> PyResult<Bound<'py, PyAny>> {
        let (state, sim) = open(&mut lock(&self.inner))?
            .with_match(slot, |m| (StateRecord::of(m), m.config().sim.clone()))
            .ok_or_else(|| value_error(format!("no match in slot {slot}: reset first")))?;
        let frame = py.detach(|| naosoccer_render::draw_frame(&sim, &state, width));
        let (h, w) = (frame.height as usize, frame.width as usize);
        Ok(PyArray1::from_vec(py, frame.pixels)
            .reshape([h, w, 3])?
            .into_any())
    }

    /// Starts every slot's first match (slot `i`: seed `seed + i`); returns
    /// `(obs, masks)`.
    fn reset<'py>(&self, py: Python<'py>, seed: u64) -> PyResult<Bound<'py, PyAny>> {
        let inner = &self.inner;
        let out =
            py.detach(|| -> PyResult<StepOut> { Ok(open(&mut lock(inner))?.reset(seed)?) })?;
        let (n, r, d, a) = self.shape;
        let obs = PyArray1::from_vec(py, out.obs).reshape([n, r, d])?;
        let masks = PyArray1::from_vec(py, out.masks).reshape([n, r, a])?;
        Ok((obs, masks).into_pyobject(py)?.into_any())
    }

    /// One control tick of every match. `actions`: int64, one per
    /// controlled robot, slot-major. Returns `(obs, rewards, terminated,
    /// masks, finished)`, `finished` a list of dicts for the matches that
    /// ended (already restarted: `obs` and `masks` are the new match's).
    fn step<'py>(
        &self,
        py: Python<'py>,
        actions: PyReadonlyArray1<'py, i64>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let acts = actions.as_slice().map_err(value_error)?.to_vec();
        drop(actions);
        let inner = &self.inner;
        let out =
            py.detach(|| -> PyResult<StepOut> { Ok(open(&mut lock(inner))?.step(&acts)?) })?;
        let (n, r, d, a) = self.shape;
        let obs = PyArray1::from_vec(py, out.obs).reshape([n, r, d])?;
        let rewards = PyArray1::from_vec(py, out.rewards).reshape([n, r])?;
        let terminated = PyArray1::from_vec(py, out.terminated);
        let masks = PyArray1::from_vec(py, out.masks).reshape([n, r, a])?;
        let finished = PyList::empty(py);
        for f in out.finished {
            finished.append(finished_dict(py, f, (r, d))?)?;
        }
        Ok((obs, rewards, terminated, masks, finished)
            .into_pyobject(py)?
            .into_any())
    }

    /// Each slot's current match seed.
    fn seeds(&self) -> PyResult<Vec<u64>> {
        Ok(open(&mut lock(&self.inner))?.seeds())
    }

    /// Each slot's current tick.
    fn ticks(&self) -> PyResult<Vec<u64>> {
        Ok(open(&mut lock(&self.inner))?.ticks())
    }

    /// Each slot's current score as (blue, red).
    fn scores(&self) -> PyResult<Vec<(u32, u32)>> {
        Ok(open(&mut lock(&self.inner))?
            .scores()
            .into_iter()
            .map(|s| (s.blue, s.red))
            .collect())
    }

    /// Each slot's current state hash.
    fn state_hashes(&self) -> PyResult<Vec<u64>> {
        Ok(open(&mut lock(&self.inner))?.state_hashes())
    }

    /// Writes a PPO actor that reads this env's observations and chooses
    /// among its actions as a team directory (`config.json`,
    /// `final.safetensors`) that `naosoccer eval --blue ppo:DIR` plays.
    /// `layers`: `(weight, bias)` float32 arrays per linear layer, weight
    /// `(outputs, inputs)` as torch's `nn.Linear` holds it, tanh between
    /// layers, the last layer's outputs the logits.
    fn write_team(
        &self,
        dir: &str,
        layers: Vec<(PyReadonlyArray2<'_, f32>, PyReadonlyArray1<'_, f32>)>,
    ) -> PyResult<()> {
        let mut out = Vec::with_capacity(layers.len());
        for (i, (w, b)) in layers.iter().enumerate() {
            let [rows, cols] = w.shape() else {
                return Err(value_error(format!("layer {i}: the weight is not 2-D")));
            };
            out.push(Layer {
                weight: w.as_array().iter().copied().collect(),
                rows: *rows,
                cols: *cols,
                bias: b.as_array().iter().copied().collect(),
            });
        }
        let mut env = lock(&self.inner);
        let env = open(&mut env)?;
        write_ppo_team(std::path::Path::new(dir), &out, env.scale(), env.decision())
            .map_err(value_error)
    }
}

fn lock(m: &Mutex<Option<VecMatches>>) -> MutexGuard<'_, Option<VecMatches>> {
    // A panic while stepping is caught where it happens (the env returns
    // `VecEnvError::Panicked`); one anywhere else poisons the lock, the
    // matches are then in an unknown state, and the next call says so by
    // panicking too.
    m.lock().expect("a previous call panicked")
}

/// The env, unless it was closed.
fn open<'a>(env: &'a mut MutexGuard<'_, Option<VecMatches>>) -> PyResult<&'a mut VecMatches> {
    env.as_mut()
        .ok_or_else(|| PyRuntimeError::new_err("the env is closed"))
}

fn finished_dict<'py>(
    py: Python<'py>,
    f: Finished,
    (r, d): (usize, usize),
) -> PyResult<Bound<'py, PyDict>> {
    let dict = PyDict::new(py);
    dict.set_item("slot", f.slot)?;
    dict.set_item("seed", f.seed)?;
    dict.set_item("ticks", f.ticks)?;
    let score = PyDict::new(py);
    score.set_item("blue", f.score.blue)?;
    score.set_item("red", f.score.red)?;
    dict.set_item("score", score)?;
    let stats = PyDict::new(py);
    for (name, t) in [("blue", &f.stats.blue), ("red", &f.stats.red)] {
        let s = PyDict::new(py);
        s.set_item("goals", t.goals)?;
        s.set_item("control_rate", t.control_rate)?;
        s.set_item("passes", t.passes)?;
        s.set_item("aimed_passes", t.aimed_passes)?;
        s.set_item("shots", t.shots)?;
        s.set_item("falls", t.falls)?;
        s.set_item("out_of_bounds", t.out_of_bounds)?;
        stats.set_item(name, s)?;
    }
    dict.set_item("stats", stats)?;
    dict.set_item("state_hash", format!("{:016x}", f.state_hash))?;
    if let Some(s) = f.scenario {
        let e = PyDict::new(py);
        e.set_item("name", s.name)?;
        e.set_item("ending", s.ending)?;
        e.set_item("success", s.success)?;
        e.set_item("ticks", s.ticks)?;
        dict.set_item("scenario", e)?;
    }
    dict.set_item("obs", PyArray1::from_vec(py, f.obs).reshape([r, d])?)?;
    Ok(dict)
}

/// The extension module.
#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<VecMatchesPy>()?;
    m.add("OBS_VERSION", naosoccer_policy::OBS_VERSION)?;
    m.add("OBS_VERSION_LATEST", naosoccer_policy::OBS_VERSION_LATEST)?;
    m.add("STATE_NAMES", state::state_names())?;
    m.add(
        "ACTION_NAMES",
        naosoccer_policy::actions::ACTION_NAMES.to_vec(),
    )?;
    m.add("VERSION", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
