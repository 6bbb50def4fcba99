"""``NaoSoccerParallelEnv``: one team of a naosoccer match as a PettingZoo
``ParallelEnv``, each robot an agent, over the socket protocol (lockstep).

For agents in other processes or on other machines; one match stepped in
this process, with no server, is :func:`naosoccer.parallel_env`.
"""

from __future__ import annotations

import functools
import os
from typing import Any, Callable, Dict, List, Optional, Sequence, Tuple, Union

import numpy as np
from gymnasium import spaces
from pettingzoo import ParallelEnv

from . import protocol
from .client import Client
from .errors import NaoSoccerError, ProtocolError
from .obs import (
    _SCORE,
    _TIME,
    OBS_DIM,
    OBS_HIGH,
    OBS_LOW,
    FieldScale,
    ObservationEncoder,
    SCORE_SCALE,
    RewardWeights,
    team_rewards,
)
from .server import LocalServer

#: The ladder of built-in teams, weakest first (``"scripted:3"`` plays as ``"scripted"``).
SCRIPTED_LEVELS = tuple(f"scripted:{n}" for n in range(1, 6))
OPPONENTS = ("scripted", *SCRIPTED_LEVELS, "idle", "client")


class NaoSoccerParallelEnv(ParallelEnv):
    """A PettingZoo ``ParallelEnv`` in which every robot of ``team`` is an agent.

    Agents are ``f"{team}_{i}"`` for players 0..3. Observations are float32
    vectors of :data:`naosoccer.obs.OBS_DIM` (layout in docs/PYTHON.md),
    actions ``Discrete(5)``: 0 forward, 1 turn_left, 2 turn_right, 3 shoot,
    4 stay. One ``step`` is one control tick of the match (lockstep: the server
    waits for the four actions). Rewards are each robot's reward as the server
    sends it (protocol 1.1+: the ``[reward]`` section of the server's match
    configuration, the learning crate's MDP); with ``reward_weights`` they are
    computed here instead by :func:`naosoccer.obs.team_rewards` with those
    weights (also against a 1.0 server, which sends none). The episode is the whole match: when
    its clock runs out every agent is terminated (truncated if the server
    shuts down or an admin ends the match) and the final ``infos`` carry the match statistics.

    Where the match comes from:

    * default: a private server is started (``naosoccer server`` on a free
      loopback port, binary from ``binary``, ``$NAOSOCCER_BIN`` or the
      repository's ``target/``) and stopped by :meth:`close`;
    * ``host``/``port``: a running server. With ``admin_token`` every
      ``reset`` creates a fresh match (so ``seed``, ``minutes`` and the
      opponent apply); without it ``reset`` joins ``match_id`` (or the oldest
      match with free slots for the team) as it is.

    ``timeout`` bounds the wait for any one message from the server, in
    seconds (``None``: no bound); raise it when the opponent is a slow client.

    ``deadline_ms`` is the lockstep deadline of the matches this env
    creates: by default the server's maximum (10 minutes), so that a learner
    pausing for a gradient update does not have ticks played without it. A
    client that disconnects frees the match at once (its robots then stand).

    ``scenario`` (protocol 1.5): every match this env creates starts from
    this scenario (docs/SCENARIOS.md), a path or the file's TOML text (see
    :func:`naosoccer.protocol.scenario_text`), with the env's ``team`` as the
    scenario's own team, drawn from the match's seed; the episode ends when
    the scenario's play ends (terminated), and the final ``infos`` carry
    ``scenario``, how it ended (``match_end``'s). The robots the file does not
    list are out of play: their observations hold them at their parking
    spots and their actions are ignored. The opponents play ``opponent``
    (not the file's ``opponent``). It needs the admin token (a private server
    has it).

    ``opponent``: ``"scripted"`` (the server's built-in team),
    ``"scripted:1"`` ... ``"scripted:5"`` (the ladder of built-in teams,
    weakest first; ``"scripted:3"`` is ``"scripted"``), ``"idle"``
    (standing robots) or ``"client"`` (the match waits until another client,
    e.g. a second env with ``team="red"``, has joined the other team: pass it
    the ``match_id`` this env reports through ``on_match`` or
    ``infos[...]["match_id"]``, or give both ``reset(options={"match_id": ...})``).
    """

    metadata = {"name": "naosoccer_v1", "render_modes": [], "is_parallelizable": True}

    def __init__(
        self,
        *,
        team: str = "blue",
        opponent: str = "scripted",
        minutes: Optional[float] = None,
        seed: Optional[int] = None,
        host: Optional[str] = None,
        port: int = 7878,
        token: Optional[str] = None,
        admin_token: Optional[str] = None,
        match_id: Optional[int] = None,
        binary: Optional[str] = None,
        server_args: Sequence[str] = (),
        deadline_ms: Optional[int] = 600_000,
        field: Optional[FieldScale] = None,
        reward_weights: Optional[RewardWeights] = None,
        on_match: Optional[Callable[[int], None]] = None,
        timeout: float = 120.0,
        scenario: Optional[Union[str, "os.PathLike[str]"]] = None,
    ) -> None:
        if team not in protocol.TEAMS:
            raise ValueError(f"team must be 'blue' or 'red', not {team!r}")
        if opponent not in OPPONENTS:
            raise ValueError(f"opponent must be one of {OPPONENTS}, not {opponent!r}")
        self.team = team
        self.opponent = opponent
        self.scenario = protocol.scenario_text(scenario) if scenario is not None else None
        self.minutes = minutes
        self.deadline_ms = deadline_ms
        self.field = field
        self.reward_weights = reward_weights
        self.on_match = on_match
        self.timeout = timeout
        self._next_seed = seed
        self._match_id_option = match_id
        self.possible_agents: List[str] = [f"{team}_{p}" for p in range(protocol.PLAYERS_PER_TEAM)]
        self.agents: List[str] = []
        self.render_mode = None
        self._obs_space = spaces.Box(low=OBS_LOW, high=OBS_HIGH, shape=(OBS_DIM,), dtype=np.float32)
        self._act_space = spaces.Discrete(len(protocol.ACTIONS))

        self.server: Optional[LocalServer] = None
        if host is None:
            self.server = LocalServer(binary, args=list(server_args))
            host, port = self.server.host, self.server.port
            token = token or self.server.tokens[team]
            admin_token = admin_token or self.server.tokens["admin"]
        if token is None:
            raise ValueError(f"connecting to {host}:{port} needs the {team} team's token")
        self.host, self.port = host, port
        self.token = token
        self.admin_token = admin_token
        if self.scenario is not None and admin_token is None:
            raise ValueError("scenario needs admin_token: only the admin creates matches from a scenario")
        self.client: Optional[Client] = None
        self.match_id: Optional[int] = None
        self.joined: Optional[Dict[str, Any]] = None
        self._encoder = ObservationEncoder(field or FieldScale())
        self._tick = 0
        self._last: Optional[Dict[str, Any]] = None
        self._last_vecs: List[np.ndarray] = []
        self._last_rewards: List[Optional[float]] = []
        self._in_match = False

    # ------------------------------------------------------------ spaces

    @functools.lru_cache(maxsize=None)
    def observation_space(self, agent: str) -> spaces.Box:
        return self._obs_space

    @functools.lru_cache(maxsize=None)
    def action_space(self, agent: str) -> spaces.Discrete:
        return self._act_space

    # ------------------------------------------------------------ episode

    def reset(
        self, seed: Optional[int] = None, options: Optional[Dict[str, Any]] = None
    ) -> Tuple[Dict[str, np.ndarray], Dict[str, Dict[str, Any]]]:
        """Starts a new match and returns the first observations.

        ``seed`` seeds the new match when this env creates it; a reset
        without one plays the seed after the previous match's (starting from
        the constructor's ``seed``; with none at all the server picks).
        ``options`` may hold ``"match_id"`` (join that match instead of
        creating one) and ``"minutes"``.
        """
        options = options or {}
        if seed is not None:
            self._next_seed = seed
            self._obs_space.seed(seed)
            self._act_space.seed(seed)
        match_seed = self._next_seed
        if match_seed is not None:
            # Later resets without a seed play the next seeds, not the same match again.
            self._next_seed = match_seed + 1
        self._leave()
        if self.client is None or self.client.closed:
            self.client = Client(self.host, self.port, timeout=self.timeout)
        match_id = options.get("match_id", self._match_id_option)
        if match_id is None and self.admin_token is not None:
            two_clients = self.opponent == "client"
            info = self.client.create_match(
                self.admin_token,
                seed=match_seed,
                minutes=options.get("minutes", self.minutes),
                mode="lockstep",
                fill="scripted" if self.opponent == "client" else self.opponent,
                start_players=2 * protocol.PLAYERS_PER_TEAM if two_clients else protocol.PLAYERS_PER_TEAM,
                deadline_ms=self.deadline_ms,
                scenario=self.scenario,
                scenario_team=self.team if self.scenario is not None else None,
            )
            match_id = info["match_id"]
        self.joined = self.client.join(self.team, self.token, range(protocol.PLAYERS_PER_TEAM), match_id)
        self.match_id = int(self.joined["match_id"])
        self._in_match = True
        if self.on_match is not None:
            self.on_match(self.match_id)
        control_hz = float(self.joined["control_hz"])
        self._encoder = ObservationEncoder(self._field_scale(), float(self.joined["total_ticks"]) / control_hz)
        msg = self.client.recv()
        if msg["type"] != "observation":
            raise ProtocolError(f"expected the first observation of match {self.match_id}, got {msg['type']!r}")
        self.agents = list(self.possible_agents)
        self._take(msg)
        obs = dict(zip(self.agents, self._last_vecs))
        # The first observation carries the events of the tick that led to
        # it when the match was already running (none at a kick-off).
        events = self._events(msg.get("events", []))
        infos = {a: self._info(p, events) for p, a in enumerate(self.agents)}
        return obs, infos

    def step(self, actions: Dict[str, Any]) -> Tuple[
        Dict[str, np.ndarray],
        Dict[str, float],
        Dict[str, bool],
        Dict[str, bool],
        Dict[str, Dict[str, Any]],
    ]:
        """Plays one control tick with ``actions`` (agent -> 0..4 or a name).

        A live agent missing from ``actions`` stays (its action is sent as
        ``stay``, so the lockstep server need not wait for its deadline). An
        action the server rejects raises :class:`NaoSoccerError` with the
        server's code; the env must then be ``reset``.
        """
        if not self.agents or self.client is None or self._last is None:
            raise RuntimeError("step() needs a running episode: call reset() first (also after an error)")
        pairs = [(p, actions.get(a, protocol.STAY)) for p, a in enumerate(self.possible_agents)]
        self.client.send_actions(self._tick, pairs)
        try:
            msg = self.client.recv()
        except (NaoSoccerError, ProtocolError):
            # The server rejected the actions (the tick is then played
            # without them) or the connection broke: the episode cannot go on
            # in step with the server, so the next call must be reset().
            self._last = None
            raise
        before = self._last
        if msg["type"] == "observation":
            self._take(msg)
            after: Optional[Dict[str, Any]] = self._last
            goals_for = after["score"]["own"] - before["score"]["own"]
            goals_against = after["score"]["opponent"] - before["score"]["opponent"]
            rew = self._rewards(self._last_rewards, after, goals_for, goals_against)
            events = self._events(msg.get("events", []))
            agents = self.agents
            obs = dict(zip(agents, self._last_vecs))
            rewards = dict(zip(agents, rew))
            infos = {a: self._info(p, events) for p, a in enumerate(agents)}
            done = dict.fromkeys(agents, False)
            return obs, rewards, done, dict(done), infos
        if msg["type"] == "match_end":
            return self._finish(msg, before)
        raise ProtocolError(f"unexpected {msg['type']!r} during match {self.match_id}")

    def _finish(self, end: Dict[str, Any], before: Dict[str, Any]):
        self._in_match = False
        other = "red" if self.team == "blue" else "blue"
        own, opp = end["score"][self.team], end["score"][other]
        goals_for = own - before["score"]["own"]
        goals_against = opp - before["score"]["opponent"]
        sent = end.get("rewards", {}).get(self.team)
        rew = self._rewards(sent or [None] * protocol.PLAYERS_PER_TEAM, None, goals_for, goals_against)
        events = self._events(end.get("events", []))
        # No observation follows the last tick; the last one stands in, with
        # the clock at zero and the final score (copies: the caller may still
        # hold the previous step's arrays).
        vecs = [v.copy() for v in self._last_vecs]
        for v in vecs:
            v[_TIME] = 0.0
            v[_SCORE] = min(own * SCORE_SCALE, OBS_HIGH[_SCORE])
            v[_SCORE + 1] = min(opp * SCORE_SCALE, OBS_HIGH[_SCORE + 1])
        agents = self.agents
        obs = dict(zip(agents, vecs))
        rewards = dict(zip(agents, rew))
        # Stopped before its clock ran out (the server stopping, or an admin
        # ending the match): the episode is truncated, not terminated.
        shutdown = end.get("reason") in ("shutdown", "ended")
        terminations = dict.fromkeys(agents, not shutdown)
        truncations = dict.fromkeys(agents, shutdown)
        infos = {}
        for p, a in enumerate(agents):
            info = self._info(p, events)
            info["score"] = {"own": own, "opponent": opp}
            info["match_end"] = end
            info["stats"] = end["stats"]
            info["goals_by_phase"] = goals_by_phase(end["stats"])
            if "scenario" in end:
                info["scenario"] = end["scenario"]
            infos[a] = info
        self.agents = []
        return obs, rewards, terminations, truncations, infos

    def _take(self, msg: Dict[str, Any]) -> None:
        observations = msg["observations"]
        if len(observations) != protocol.PLAYERS_PER_TEAM:
            raise ProtocolError(f"expected {protocol.PLAYERS_PER_TEAM} observations, got {len(observations)}")
        self._tick = int(msg["tick"])
        self._last = observations[0]
        self._last_vecs = self._encoder.encode_team(observations)
        self._last_rewards = [o.get("reward") for o in observations]

    def _rewards(
        self,
        sent: Sequence[Optional[float]],
        after: Optional[Dict[str, Any]],
        goals_for: int,
        goals_against: int,
    ) -> List[float]:
        """The server's rewards, unless weights were given or it sent none."""
        if self.reward_weights is None and all(r is not None for r in sent):
            return [float(r) for r in sent]  # type: ignore[arg-type]
        w = self.reward_weights or RewardWeights()
        return team_rewards(w, after, goals_for, goals_against)

    def _field_scale(self) -> FieldScale:
        """The ``field`` given, else the pitch ``joined`` announced
        (protocol 1.2), else the built-in configuration's."""
        if self.field is not None:
            return self.field
        pitch = self.joined.get("pitch") if self.joined else None
        if pitch:
            return FieldScale(float(pitch["field_length"]), float(pitch["field_width"]))
        return FieldScale()

    def _events(self, events: List[Dict[str, Any]]) -> List[Dict[str, Any]]:
        """The referee's events of the tick, as the server pushed them
        (protocol 1.2), each with ``side`` (``"own"`` or ``"opponent"``) for
        events of a team or robot and ``player`` for events of one robot."""
        return [_with_side(e, self.team) for e in events]

    def _info(self, player: int, events: List[Dict[str, Any]]) -> Dict[str, Any]:
        last = self._last or {}
        control = last.get("control", [False] * protocol.PLAYERS_PER_TEAM)
        if any(control):
            possession: Optional[str] = "own"
        elif last.get("opponent_control"):
            possession = "opponent"
        else:
            possession = None
        return {
            "match_id": self.match_id,
            "tick": self._tick,
            "player": player,
            "score": dict(last.get("score", {"own": 0, "opponent": 0})),
            "possession": possession,
            "controller": next((p for p, c in enumerate(control) if c), None),
            "events": events,
        }

    # ------------------------------------------------------------ lifecycle

    def _leave(self) -> None:
        if self.client is not None and not self.client.closed and self._in_match:
            try:
                self.client.leave()
            except (NaoSoccerError, ProtocolError):
                # A broken connection is replaced on the next reset.
                self.client.close()
        self._in_match = False
        self.agents = []

    def close(self) -> None:
        self._leave()
        if self.client is not None:
            self.client.close()
            self.client = None
        if self.server is not None:
            self.server.stop()
            self.server = None

    def render(self) -> None:
        return None

    def state(self) -> np.ndarray:
        return self._last_vecs[0].copy() if self._last_vecs else np.zeros(OBS_DIM, np.float32)



def _with_side(event: Dict[str, Any], team: str) -> Dict[str, Any]:
    """A copy of a server event with the env's team-relative keys added.

    Events name teams (``team``) and robots (``robot``, ``from``: 0..3 blue
    players, 4..7 red) in world terms; positions stay in the world frame.
    """
    e = dict(event)
    robot = e.get("robot", e.get("from"))
    owner: Optional[str] = e.get("team")
    if owner is None and isinstance(robot, int):
        owner = protocol.TEAMS[robot // protocol.PLAYERS_PER_TEAM]
        if "robot" in e:
            e["player"] = robot % protocol.PLAYERS_PER_TEAM
    if owner is not None:
        e["side"] = "own" if owner == team else "opponent"
    return e


#: The goals-by-phase fields of a team's ``match_end`` statistics (protocol 1.4).
GOAL_PHASES = ("open_play", "restart", "own_goal", "disallowed")


def goals_by_phase(stats: Dict[str, Any]) -> Dict[str, Dict[str, int]]:
    """Per team, its goals by phase from ``match_end``'s ``stats``:
    ``open_play``, ``restart`` (from its own kick-off or set play),
    ``own_goal`` (the other team's own goals; the three sum to its goals) and
    ``disallowed`` (goals straight from its kick-off, which did not count).
    0 where a server older than protocol 1.4 sent none."""
    return {team: {p: int(s.get(f"goals_{p}", 0)) for p in GOAL_PHASES} for team, s in stats.items()}
