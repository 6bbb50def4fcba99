"""naosoccer: the naosoccer simulator for Python.

* :class:`VectorEnv`: many matches stepped in this process by the native
  extension, as a Gymnasium vector env (numpy in and out).
* :func:`parallel_env`, :func:`env`: one match stepped in this process as a
  PettingZoo ``ParallelEnv`` / ``AECEnv`` (each robot an agent).
* :func:`binary_path`: the ``naosoccer`` binary the package carries.
* :func:`export_policy`: a PPO actor trained on a :class:`VectorEnv` written as
  a team directory that ``naosoccer eval --blue ppo:DIR`` plays.
* :class:`Client`: the socket protocol (handshake, matches, join, actions).
* :class:`NaoSoccerParallelEnv`: one team of a match on a server (over the
  socket protocol) as a PettingZoo ``ParallelEnv``.
* :class:`LocalServer`: ``naosoccer server`` as a subprocess on a free port.
* :mod:`naosoccer.evaluation`, :mod:`naosoccer.league`: ``naosoccer eval``
  played in blocks of matches and merged by the binary; round-robin standings.
* :mod:`naosoccer.ray` (the ``ray`` extra): evaluations, leagues and RLlib
  training on a Ray cluster (docs/RAY.md).

See docs/PYTHON.md in the repository.
"""

from .client import Client
from .errors import NaoSoccerError, ProtocolError, ServerStartError
from .export import export_policy
from .obs import (
    FEATURE_NAMES,
    OBS_DIM,
    OBS_VERSION,
    FieldScale,
    ObservationEncoder,
    RewardWeights,
    team_rewards,
)
from .parallel import TEAM_DECISION, TEAM_OBS_VERSION, ParallelMatchEnv, env, parallel_env, raw_env
from .protocol import ACTIONS, PROTOCOL_VERSION
from .server import LocalServer, binary_path, find_binary
from .socket_env import OPPONENTS, NaoSoccerParallelEnv
from .vector import ACTION_NAMES, VectorEnv, team_layout

__version__ = "0.1.0"

__all__ = [
    "ACTIONS",
    "ACTION_NAMES",
    "Client",
    "FEATURE_NAMES",
    "FieldScale",
    "LocalServer",
    "NaoSoccerError",
    "NaoSoccerParallelEnv",
    "OBS_DIM",
    "OBS_VERSION",
    "OPPONENTS",
    "ObservationEncoder",
    "PROTOCOL_VERSION",
    "ParallelMatchEnv",
    "ProtocolError",
    "RewardWeights",
    "ServerStartError",
    "TEAM_DECISION",
    "TEAM_OBS_VERSION",
    "VectorEnv",
    "binary_path",
    "env",
    "export_policy",
    "find_binary",
    "parallel_env",
    "raw_env",
    "team_layout",
    "team_rewards",
]
