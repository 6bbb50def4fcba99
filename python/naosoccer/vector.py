"""``VectorEnv``: many matches stepped inside this process by the native
extension, one control tick of every match per ``step``, as a Gymnasium
vector env (auto-reset in the same step).

Each match is one sub-environment whose "agent" is a whole team: its
observation is one row per controlled robot, its action one index per
robot. No sockets, no JSON: numpy arrays go to the extension and back, and
the GIL is released while the matches step.
"""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any, Dict, List, Mapping, Optional, Sequence, Tuple, Union

import numpy as np
from gymnasium import spaces
from gymnasium.vector import AutoresetMode
from gymnasium.vector import VectorEnv as _GymVectorEnv
from gymnasium.vector.utils import batch_space

from .protocol import scenario_text

try:
    from . import _native
except ImportError as e:  # pragma: no cover - depends on how the package was installed
    _native = None
    _IMPORT_ERROR: Optional[ImportError] = e
else:
    _IMPORT_ERROR = None

#: Action names by index (a team uses the first ``n`` of them, see ``actions``).
ACTION_NAMES = (
    "forward",
    "turn_left",
    "turn_right",
    "shoot",
    "stay",
    "pass",
    "support",
    "approach",
    "defend",
    "give",
)

_TEAMS = ("blue", "red", "both")

#: ``scenario=``: a path, a scenario's TOML text, or a sequence of them.
ScenarioArg = Union[str, "os.PathLike[str]", Sequence[Union[str, "os.PathLike[str]"]]]


def _scenario_args(
    scenario: Optional[ScenarioArg], weights: Optional[Sequence[float]]
) -> Tuple[Union[None, str, List[str]], Optional[List[float]]]:
    """The in-process envs' ``scenario`` and ``scenario_weights`` as the
    native extension takes them: one scenario's text (a path or a text, as
    :func:`naosoccer.protocol.scenario_text` reads it), or for any other
    sequence (a list, a tuple) the list of its entries' texts; the weights
    as floats. An empty list, and weights that are not numbers, raise
    ``ValueError``; the extension checks the rest."""
    if scenario is None:
        texts: Union[None, str, List[str]] = None
    elif isinstance(scenario, (str, bytes, os.PathLike)):
        texts = scenario_text(scenario)
    else:
        try:
            entries = list(scenario)
        except TypeError:
            raise TypeError(
                f"scenario is a path, a scenario's TOML text or a list of them, got {type(scenario).__name__}"
            ) from None
        if not entries:
            raise ValueError("scenario: an empty list: give at least one scenario")
        texts = [scenario_text(s) for s in entries]
    if weights is None:
        return texts, None
    if isinstance(weights, (str, bytes)):
        raise ValueError(f"scenario_weights: a sequence of numbers, one a scenario, got {weights!r}")
    try:
        return texts, [float(w) for w in weights]
    except (TypeError, ValueError):
        raise ValueError(f"scenario_weights: a sequence of numbers, one a scenario, got {weights!r}") from None


def _require_native() -> Any:
    if _native is None:
        raise ImportError(
            "naosoccer's native extension is not built: install the package "
            "(pip install ./python, or a wheel from scripts/wheel), or build it "
            "in place with scripts/wheel --in-place"
        ) from _IMPORT_ERROR
    return _native


def team_layout(spec: str) -> Tuple[int, Optional[Dict[str, Any]]]:
    """The observation layout version and decision-level action set of a
    trained team (``ppo:DIR``, ``dqn:DIR`` or ``DIR``, a directory with the
    team's ``config.json``), for an env whose robots observe and act as that
    team's do."""
    path = Path(spec.split(":", 1)[1] if ":" in spec and not os.path.exists(spec) else spec)
    config = path / "config.json" if path.is_dir() else path
    with open(config) as f:
        c = json.load(f)
    algo = c.get("algo", "ppo")
    return int(c.get("obs_version", 1)), (c.get(algo) or {}).get("decision")


class VectorEnv(_GymVectorEnv):
    """``num_matches`` matches in this process, one team (or both) driven
    from Python.

    * observations: float32 ``(num_matches, robots, obs_dim)``, one row per
      controlled robot (player order; blue's four then red's with
      ``team="both"``), each in its own team's frame, in layout
      ``obs_version`` (docs/PYTHON.md);
    * actions: ints ``(num_matches, robots)``, indices into
      :data:`ACTION_NAMES` below the action count (5, or 6 to 10 with the
      ``decision`` settings of the shipped teams);
    * rewards: float32 ``(num_matches, robots)``, each robot's reward under
      the match configuration's ``[reward]``;
    * terminations: ``(num_matches,)``, true on the tick a match ends (its
      clock ran out); truncations always false;
    * infos: ``action_mask`` (bool ``(num_matches, robots, actions)``: what a
      shipped team with these settings may choose), and for matches that
      ended, ``final_obs`` and ``final_info`` (score, statistics, seed,
      ticks, state hash) as Gymnasium's same-step auto-reset gives them.

    A match that ends is restarted in the same ``step``; the returned
    observation is the new match's kick-off. Slot ``i``'s ``e``-th match
    after ``reset(seed=s)`` has seed ``s + i + e * num_matches``.

    ``scenario`` (a path or the file's TOML text, see
    :func:`naosoccer.protocol.scenario_text`): every match starts from this
    scenario (docs/SCENARIOS.md), drawn from its seed, with ``team`` as the
    scenario's own team (blue with ``team="both"``), and ends (terminated)
    when the scenario's play ends; its ``final_info`` then holds
    ``scenario``: ``name`` (the scenario's), ``ending`` (the end condition's
    name), ``success`` and ``ticks`` (played from the scenario's start). The
    restarted match starts from the scenario again. ``opponent`` defaults to
    the file's ``opponent`` then, as in ``naosoccer match --scenario``;
    without a scenario to ``"scripted"``.

    ``scenario`` may also be a list (any sequence) of scenarios: every match
    start (each reset's, each restart) draws one from the match's seed, with
    chances in proportion to ``scenario_weights`` (one non-negative number
    a scenario; default equal). ``opponent`` then defaults to the one the
    files name; where they name different built-in policies each match
    plays its own scenario's (``env.opponent`` is ``"per scenario"``), and a
    trained team among them needs ``opponent=`` (docs/PYTHON.md).
    """

    metadata = {"autoreset_mode": AutoresetMode.SAME_STEP, "render_modes": []}

    def __init__(
        self,
        num_matches: int = 8,
        *,
        team: str = "blue",
        opponent: Optional[str] = None,
        minutes: Optional[float] = None,
        seed: Optional[int] = None,
        obs_version: Optional[int] = None,
        decision: Optional[Mapping[str, Any]] = None,
        like: Optional[str] = None,
        match_config: Optional[Union[str, os.PathLike]] = None,
        threads: Optional[int] = None,
        scenario: Optional[ScenarioArg] = None,
        scenario_weights: Optional[Sequence[float]] = None,
    ) -> None:
        native = _require_native()
        if team not in _TEAMS:
            raise ValueError(f"team must be one of {_TEAMS}, got {team!r}")
        if like is not None:
            version, dec = team_layout(like)
            obs_version = version if obs_version is None else obs_version
            decision = dec if decision is None else decision
        if obs_version is None:
            obs_version = native.OBS_VERSION
        config_toml = Path(match_config).read_text() if match_config is not None else None
        if threads is None:
            threads = min(os.cpu_count() or 1, num_matches)
        self.team = team
        #: The scenario's TOML text, or the list's texts (``None``: the kick-off).
        self.scenario, weights = _scenario_args(scenario, scenario_weights)
        self.obs_version = int(obs_version)
        self.decision = dict(decision) if decision is not None else None
        self._native = native.VecMatches(
            num_matches,
            team,
            opponent,
            self.obs_version,
            json.dumps(self.decision) if self.decision is not None else None,
            config_toml,
            minutes,
            threads,
            self.scenario,
            scenario_weights=weights,
        )
        #: The opponents' policy spec as resolved (``None`` with ``team="both"``;
        #: ``"per scenario"``: each match plays its own scenario's).
        self.opponent = None if team == "both" else self._native.opponent
        #: Threads stepping the matches, this one included (at most ``num_matches``).
        self.threads = self._native.threads
        n, robots, dim, actions = self._native.shape
        self.num_envs = n
        self.robots = robots
        self.obs_dim = dim
        self.num_actions = actions
        #: Row names: ``blue_0`` ... (the controlled robots, in row order).
        self.agents = [f"{t}_{p}" for t in (("blue", "red") if team == "both" else (team,)) for p in range(4)]
        self.action_names = ACTION_NAMES[:actions]
        self.single_observation_space = spaces.Box(-np.inf, np.inf, (robots, dim), np.float32)
        self.single_action_space = spaces.MultiDiscrete(np.full(robots, actions))
        self.observation_space = batch_space(self.single_observation_space, n)
        self.action_space = batch_space(self.single_action_space, n)
        self._seed = seed
        self._seeds = np.random.default_rng(seed)
        self._started = False

    def reset(
        self, *, seed: Optional[int] = None, options: Optional[Dict[str, Any]] = None
    ) -> Tuple[np.ndarray, Dict[str, Any]]:
        """Starts every slot's first match: slot ``i`` with seed ``seed + i``.
        Without a seed: the constructor's on the first reset, then seeds
        drawn from a generator the constructor's seed starts."""
        if seed is None:
            if self._seed is not None and not self._started:
                seed = self._seed
            else:
                seed = int(self._seeds.integers(0, 2**63))
        elif not 0 <= seed < 2**64:
            raise ValueError(f"seed must be in 0..2^64-1, got {seed}")
        else:
            # Later resets without a seed draw from this one's stream.
            self._seeds = np.random.default_rng(seed)
        self._started = True
        obs, masks = self._native.reset(seed)
        return obs, {"action_mask": masks, "_action_mask": np.ones(self.num_envs, dtype=bool)}

    def step(
        self, actions: Any
    ) -> Tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, Dict[str, Any]]:
        if not self._started:
            raise RuntimeError("call reset() before step()")
        acts = np.ascontiguousarray(actions, dtype=np.int64).reshape(-1)
        obs, rewards, terminated, masks, finished = self._native.step(acts)
        infos: Dict[str, Any] = {"action_mask": masks, "_action_mask": np.ones(self.num_envs, dtype=bool)}
        for f in finished:
            i = f.pop("slot")
            final_obs = f.pop("obs")
            infos = self._add_info(infos, {"final_obs": final_obs, "final_info": f}, i)
        truncated = np.zeros(self.num_envs, dtype=bool)
        return obs, rewards, terminated, truncated, infos

    def close_extras(self, **kwargs: Any) -> None:
        """Stops the stepping threads and frees the matches (``close()``, or
        the env's garbage collection, calls it); the env is unusable after."""
        native = getattr(self, "_native", None)  # None: the constructor failed
        if native is not None:
            native.close()

    def seeds(self) -> List[int]:
        """Each slot's current match seed."""
        return list(self._native.seeds())

    def ticks(self) -> List[int]:
        """Each slot's current tick (0 at kick-off)."""
        return list(self._native.ticks())

    def scores(self) -> List[Tuple[int, int]]:
        """Each slot's current score, as (blue, red)."""
        return list(self._native.scores())

    def state_hashes(self) -> List[str]:
        """Each slot's current match state hash, 16 hex digits (as
        ``naosoccer match --json`` prints it)."""
        return [f"{h:016x}" for h in self._native.state_hashes()]
