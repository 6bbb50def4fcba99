"""naosoccer: a pure-Python client for the naosoccer match server.

* :class:`Client`: the socket protocol (handshake, matches, join, actions).
* :class:`NaoSoccerParallelEnv`: one team as a PettingZoo ``ParallelEnv``.
* :class:`LocalServer`: ``naosoccer server`` as a subprocess on a free port.
* :mod:`naosoccer.evaluation`, :mod:`naosoccer.league`: ``naosoccer eval``
  split into single matches and merged again; round-robin standings.
* :mod:`naosoccer.ray` (the ``ray`` extra): evaluations, leagues and RLlib
  training on a Ray cluster (docs/RAY.md).

See docs/PYTHON.md in the repository.
"""

from .client import Client
from .env import OPPONENTS, NaoSoccerParallelEnv
from .errors import NaoSoccerError, ProtocolError, ServerStartError
from .obs import (
    FEATURE_NAMES,
    OBS_DIM,
    OBS_VERSION,
    FieldScale,
    ObservationEncoder,
    RewardWeights,
    team_rewards,
)
from .protocol import ACTIONS, PROTOCOL_VERSION
from .server import LocalServer, find_binary

__version__ = "0.1.0"

__all__ = [
    "ACTIONS",
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
    "ProtocolError",
    "RewardWeights",
    "ServerStartError",
    "find_binary",
    "team_rewards",
]
