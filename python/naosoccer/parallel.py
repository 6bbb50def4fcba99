"""One match in this process as a PettingZoo env: :func:`parallel_env` (a
``ParallelEnv``) and :func:`env` (the same as an ``AECEnv``), each robot an
agent, stepped by the native extension as :class:`naosoccer.VectorEnv`
steps its matches (no server, no sockets).

The socket env (:class:`naosoccer.NaoSoccerParallelEnv`) plays a match on a
server instead: for agents in other processes or on other machines.
"""

from __future__ import annotations

import json
import os
import types
from pathlib import Path
from typing import Any, Dict, List, Mapping, Optional, Sequence, Tuple, Union

import gymnasium
import numpy as np
from gymnasium import spaces
from pettingzoo import AECEnv, ParallelEnv
from pettingzoo.utils.conversions import parallel_to_aec_wrapper
from pettingzoo.utils.wrappers import AssertOutOfBoundsWrapper, OrderEnforcingWrapper

from .vector import ACTION_NAMES, ScenarioArg, _require_native, _scenario_args, team_layout

#: The observation layout of the shipped ``ppo-team`` teams
#: (assets/policies/ppo-team-seed1/config.json): the envs' default.
TEAM_OBS_VERSION = 4

#: The decision settings (action set and masks) of the shipped ``ppo-team``
#: teams: nine actions (``pass``, ``support``, ``approach`` and ``defend``
#: after the paper's five), ``shoot`` masked out of kick reach, two chasers.
#: The envs' default.
TEAM_DECISION: Mapping[str, Any] = types.MappingProxyType({
    "persist": 3,
    "mask_shoot": True,
    "pass": True,
    "support": True,
    "support_hold": 60,
    "chasers": 2,
    "support_spot": "facing",
    "approach": True,
    "defend": True,
})

_TEAMS = ("blue", "red", "both")
_STAY = ACTION_NAMES.index("stay")


class ParallelMatchEnv(ParallelEnv):
    """One match in this process; every robot of ``team`` (both teams'
    eight with ``team="both"``) is an agent. Build it with
    :func:`naosoccer.parallel_env`; docs/PYTHON.md has the options.

    * agents: ``blue_0`` ... ``blue_3`` (or ``red_*``; with ``"both"``
      blue's four then red's), player 0 the keeper;
    * observations: float32 vectors of layout ``obs_version``, each in its
      own team's frame (as :class:`naosoccer.VectorEnv`'s rows);
    * actions: ``Discrete(num_actions)``, indices into
      :data:`naosoccer.ACTION_NAMES`; a live agent left out of the actions
      dict stays;
    * ``infos[agent]["action_mask"]``: int8, 1 where the ``decision``
      settings allow the action now (not enforced: the env plays any action
      in range);
    * one ``step`` is one control tick; the episode is the match (or the
      scenario's play): on its last step every agent is terminated and the
      infos add ``score``, ``stats``, ``seed``, ``ticks``, ``state_hash``
      (and ``scenario``: ``name``, ``ending``, ``success``, ``ticks``);
    * ``scenario`` may be a list: each reset's match draws one from its
      seed (``scenario_weights``), as :class:`naosoccer.VectorEnv`'s matches;
    * ``state()``: the world-frame global state, entries
      :attr:`state_names`; ``render()`` with ``render_mode="rgb_array"``: the
      top view ``naosoccer render --gif`` draws, uint8 ``(H, W, 3)``.
    """

    metadata = {
        "name": "naosoccer_v0",
        "render_modes": ["rgb_array"],
        "render_fps": 10,
        "is_parallelizable": True,
    }

    def __init__(
        self,
        *,
        team: str = "blue",
        opponent: Optional[str] = None,
        minutes: Optional[float] = None,
        seed: Optional[int] = None,
        obs_version: Optional[int] = None,
        decision: Optional[Mapping[str, Any]] = TEAM_DECISION,
        like: Optional[str] = None,
        match_config: Optional[Union[str, "os.PathLike[str]"]] = None,
        scenario: Optional[ScenarioArg] = None,
        scenario_weights: Optional[Sequence[float]] = None,
        render_mode: Optional[str] = None,
        render_width: int = 640,
    ) -> None:
        native = _require_native()
        if team not in _TEAMS:
            raise ValueError(f"team must be one of {_TEAMS}, got {team!r}")
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ValueError(f"render_mode must be None or one of {self.metadata['render_modes']}, got {render_mode!r}")
        if like is not None:
            version, dec = team_layout(like)
            obs_version = version if obs_version is None else obs_version
            # The default stands aside for the trained team's settings.
            decision = dec if decision is TEAM_DECISION else decision
        if obs_version is None:
            obs_version = TEAM_OBS_VERSION
        config_toml = Path(match_config).read_text() if match_config is not None else None
        self.team = team
        #: The scenario's TOML text, or the list's texts (``None``: the kick-off).
        self.scenario, weights = _scenario_args(scenario, scenario_weights)
        self.obs_version = int(obs_version)
        self.decision = dict(decision) if decision is not None else None
        self.render_mode = render_mode
        self.render_width = int(render_width)
        self._native = native.VecMatches(
            1,
            team,
            opponent,
            self.obs_version,
            json.dumps(self.decision) if self.decision is not None else None,
            config_toml,
            minutes,
            1,
            self.scenario,
            restart=False,
            scenario_weights=weights,
        )
        #: The opponents' policy spec as resolved (``None`` with ``team="both"``;
        #: ``"per scenario"``: each match plays its own scenario's).
        self.opponent = None if team == "both" else self._native.opponent
        _, robots, dim, actions = self._native.shape
        self.num_actions = actions
        self.action_names = ACTION_NAMES[:actions]
        self.obs_dim = dim
        self.metadata = {**self.metadata, "render_fps": self._native.control_hz}
        self.possible_agents: List[str] = [
            f"{t}_{p}" for t in (("blue", "red") if team == "both" else (team,)) for p in range(4)
        ]
        assert len(self.possible_agents) == robots
        self.agents: List[str] = []
        #: Names of the :meth:`state` entries, in order.
        self.state_names: Tuple[str, ...] = tuple(native.STATE_NAMES)
        self.state_space = spaces.Box(-np.inf, np.inf, (len(self.state_names),), np.float32)
        # One space object for every agent: seeded once, it samples different
        # actions for different agents.
        self._obs_space = spaces.Box(-np.inf, np.inf, (dim,), np.float32)
        self._act_space = spaces.Discrete(actions)
        self._next_seed: Optional[int] = seed
        self._seeds = np.random.default_rng()

    def observation_space(self, agent: str) -> spaces.Box:
        return self._obs_space

    def action_space(self, agent: str) -> spaces.Discrete:
        return self._act_space

    def reset(
        self, seed: Optional[int] = None, options: Optional[Dict[str, Any]] = None
    ) -> Tuple[Dict[str, np.ndarray], Dict[str, Dict[str, Any]]]:
        """Starts a match: with ``seed``, the match of that seed (``naosoccer
        match --seed``); without, the constructor's ``seed`` the first time,
        then the seed after the previous match's (a random one when no seed
        was ever given). ``options`` are not used."""
        if seed is not None:
            if not 0 <= seed < 2**64:
                raise ValueError(f"seed must be in 0..2^64-1, got {seed}")
            self._act_space.seed(seed)
            match_seed = int(seed)
        elif self._next_seed is not None:
            match_seed = self._next_seed
        else:
            match_seed = int(self._seeds.integers(0, 2**63))
        self._next_seed = (match_seed + 1) % 2**64
        obs, masks = self._native.reset(match_seed)
        self.agents = list(self.possible_agents)
        observations = {a: obs[0, k] for k, a in enumerate(self.agents)}
        infos = {a: {"action_mask": masks[0, k].astype(np.int8)} for k, a in enumerate(self.agents)}
        return observations, infos

    def step(self, actions: Mapping[str, Any]) -> Tuple[
        Dict[str, np.ndarray],
        Dict[str, float],
        Dict[str, bool],
        Dict[str, bool],
        Dict[str, Dict[str, Any]],
    ]:
        """Plays one control tick. ``actions``: agent -> action index; a live
        agent left out stays. An index out of range raises ``ValueError``."""
        if not self.agents:
            raise RuntimeError("no match in progress: call reset() (the last one ended)")
        unknown = set(actions) - set(self.agents)
        if unknown:
            raise ValueError(f"actions for agents not in play: {sorted(unknown)}")
        acts = np.array([_index(actions.get(a, _STAY)) for a in self.agents], dtype=np.int64)
        obs, rewards, terminated, masks, finished = self._native.step(acts)
        agents = self.agents
        observations = {a: obs[0, k] for k, a in enumerate(agents)}
        rews = {a: float(rewards[0, k]) for k, a in enumerate(agents)}
        infos: Dict[str, Dict[str, Any]] = {
            a: {"action_mask": masks[0, k].astype(np.int8)} for k, a in enumerate(agents)
        }
        done = bool(terminated[0])
        if finished:
            end = dict(finished[0])
            end.pop("slot")
            end.pop("obs")
            for info in infos.values():
                info.update(end)
        terminations = dict.fromkeys(agents, done)
        truncations = dict.fromkeys(agents, False)
        if done:
            self.agents = []
        return observations, rews, terminations, truncations, infos

    def state(self) -> np.ndarray:
        """The match's global state: float32 ``(len(state_names),)``, in the
        world frame (blue attacks +x), both teams' robots (docs/PYTHON.md)."""
        return self._native.state()[0]

    def render(self) -> Optional[np.ndarray]:
        """With ``render_mode="rgb_array"``: the match now, drawn as
        ``naosoccer render --gif`` draws a frame, uint8 ``(H, W, 3)``,
        ``render_width`` pixels wide. Without a render mode: ``None`` (and a
        warning)."""
        if self.render_mode is None:
            gymnasium.logger.warn("render() without a render_mode: build the env with render_mode=\"rgb_array\"")
            return None
        return self._native.render(0, self.render_width)

    def close(self) -> None:
        self.agents = []

    @property
    def match_seed(self) -> int:
        """The current (or last) match's seed."""
        return int(self._native.seeds()[0])

    @property
    def tick(self) -> int:
        """Control ticks played in the current match."""
        return int(self._native.ticks()[0])

    @property
    def score(self) -> Tuple[int, int]:
        """The current match's score, (blue, red)."""
        return tuple(self._native.scores()[0])  # type: ignore[return-value]

    def state_hash(self) -> str:
        """The current match's state hash, 16 hex digits, as ``naosoccer
        match --json`` prints it."""
        return f"{self._native.state_hashes()[0]:016x}"


def _index(action: Any) -> int:
    """An action index given as a Python or numpy integer."""
    a = np.asarray(action)
    if a.shape != () or not np.issubdtype(a.dtype, np.integer):
        raise ValueError(f"an action is an integer index, got {action!r}")
    return int(a)


def parallel_env(**kwargs: Any) -> ParallelMatchEnv:
    """One match in this process as a PettingZoo ``ParallelEnv``. Options
    (keywords): ``team``, ``opponent``, ``minutes``, ``seed``,
    ``obs_version``, ``decision``, ``like``, ``match_config``, ``scenario``,
    ``scenario_weights``, ``render_mode``, ``render_width``
    (docs/PYTHON.md)."""
    return ParallelMatchEnv(**kwargs)


def raw_env(**kwargs: Any) -> AECEnv:
    """:func:`parallel_env` turned into an ``AECEnv`` (PettingZoo's
    ``parallel_to_aec`` conversion), without the wrappers of :func:`env`."""
    return parallel_to_aec_wrapper(ParallelMatchEnv(**kwargs))


def env(**kwargs: Any) -> AECEnv:
    """One match in this process as a PettingZoo ``AECEnv``: the agents act
    in turn and the tick is played once the last live one has acted.
    :func:`raw_env` with PettingZoo's usual wrappers: an out-of-range action
    fails an assertion (``AssertOutOfBoundsWrapper``), and ``step`` before
    ``reset`` raises (``OrderEnforcingWrapper``)."""
    return OrderEnforcingWrapper(AssertOutOfBoundsWrapper(raw_env(**kwargs)))
