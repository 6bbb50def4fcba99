"""The flat observation vector and the client-side shaped reward.

Everything is in the controlled team's frame (the server mirrors red's view,
so a team always attacks +x). Positions are divided by the half-field sizes,
so the pitch spans [-1, 1] on both axes. docs/PYTHON.md lists the same layout;
a test checks that the two agree.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Dict, List, Optional, Sequence, Tuple

import numpy as np

from .protocol import PLAYERS_PER_TEAM

#: Bumped whenever the layout below changes.
OBS_VERSION = 1

#: Ball velocities are divided by this (m/s): a hard kick is a few m/s.
BALL_SPEED_SCALE = 2.0
#: Goals are multiplied by this.
SCORE_SCALE = 0.1


def _feature_names() -> List[str]:
    names: List[str] = []
    for p in range(PLAYERS_PER_TEAM):
        names += [f"own{p}_x", f"own{p}_y", f"own{p}_cos", f"own{p}_sin", f"own{p}_fallen"]
    names += ["ball_x", "ball_y", "ball_vx", "ball_vy"]
    names += [f"control{p}" for p in range(PLAYERS_PER_TEAM)]
    names += ["opponent_control"]
    for p in range(PLAYERS_PER_TEAM):
        names += [f"opp{p}_x", f"opp{p}_y", f"opp{p}_cos", f"opp{p}_sin", f"opp{p}_fallen"]
    names += [f"me{p}" for p in range(PLAYERS_PER_TEAM)]
    names += ["time_left", "score_own", "score_opponent", "ball_fwd", "ball_left"]
    return names


#: The name of every entry, in order.
FEATURE_NAMES: Tuple[str, ...] = tuple(_feature_names())
#: Length of the observation vector.
OBS_DIM = len(FEATURE_NAMES)

_IDX = {name: i for i, name in enumerate(FEATURE_NAMES)}
_OWN = _IDX["own0_x"]
_BALL = _IDX["ball_x"]
_CONTROL = _IDX["control0"]
_OPP_CONTROL = _IDX["opponent_control"]
_OPP = _IDX["opp0_x"]
_ME = _IDX["me0"]
_TIME = _IDX["time_left"]
_SCORE = _IDX["score_own"]
_REL = _IDX["ball_fwd"]


def _bounds() -> Tuple[np.ndarray, np.ndarray]:
    # Generous, finite bounds; the encoder clips to them. Positions: the ground
    # extends 0.5 m beyond the lines and goals are 1 m deep, well inside +-2.
    high = np.empty(OBS_DIM, dtype=np.float32)
    low = np.empty(OBS_DIM, dtype=np.float32)
    for i, name in enumerate(FEATURE_NAMES):
        if name.endswith(("_x", "_y")):
            low[i], high[i] = -2.0, 2.0
        elif name.endswith(("_cos", "_sin")):
            low[i], high[i] = -1.0, 1.0
        elif name in ("ball_vx", "ball_vy"):
            low[i], high[i] = -10.0, 10.0
        elif name in ("ball_fwd", "ball_left"):
            low[i], high[i] = -4.0, 4.0
        elif name.startswith("score"):
            low[i], high[i] = 0.0, 100.0
        else:  # flags, one-hot, time fraction
            low[i], high[i] = 0.0, 1.0
    return low, high


OBS_LOW, OBS_HIGH = _bounds()


@dataclass(frozen=True)
class FieldScale:
    """The pitch's size in metres (inside the lines), for normalisation.

    The env takes it from the pitch ``joined`` announces (protocol 1.2);
    the defaults are those of the server's built-in match configuration
    (assets/match.toml), for older servers.
    """

    length: float = 6.0
    width: float = 4.5


class ObservationEncoder:
    """Turns one tick's team observations into one vector per player."""

    def __init__(self, field: FieldScale = FieldScale(), match_seconds: float = 600.0) -> None:
        self.sx = 2.0 / field.length
        self.sy = 2.0 / field.width
        self.match_seconds = max(float(match_seconds), 1e-9)

    def encode_team(self, observations: Sequence[Dict[str, Any]]) -> List[np.ndarray]:
        """One float32 vector of :data:`OBS_DIM` per observation, in order.

        All observations of one tick share everything but the receiving
        player, so the common part is built once.
        """
        first = observations[0]
        sx, sy = self.sx, self.sy
        v: List[float] = []
        for r in first["own"]:
            h = r["heading"]
            v += (r["x"] * sx, r["y"] * sy, math.cos(h), math.sin(h), 1.0 if r["fallen"] else 0.0)
        b = first["ball"]
        v += (b["x"] * sx, b["y"] * sy, b["vx"] / BALL_SPEED_SCALE, b["vy"] / BALL_SPEED_SCALE)
        v += [1.0 if c else 0.0 for c in first["control"]]
        v.append(1.0 if first["opponent_control"] else 0.0)
        for r in first["opponents"]:
            h = r["heading"]
            v += (r["x"] * sx, r["y"] * sy, math.cos(h), math.sin(h), 1.0 if r["fallen"] else 0.0)
        v += (0.0, 0.0, 0.0, 0.0)
        v.append(min(max(first["time_left"] / self.match_seconds, 0.0), 1.0))
        score = first["score"]
        v += (score["own"] * SCORE_SCALE, score["opponent"] * SCORE_SCALE, 0.0, 0.0)
        base = np.asarray(v, dtype=np.float32)
        np.clip(base, OBS_LOW, OBS_HIGH, out=base)
        own = first["own"]
        out = []
        for o in observations:
            me = int(o["player"]) % PLAYERS_PER_TEAM
            vec = base.copy()
            vec[_ME + me] = 1.0
            r = own[me]
            dx, dy = b["x"] - r["x"], b["y"] - r["y"]
            c, s = math.cos(r["heading"]), math.sin(r["heading"])
            vec[_REL] = min(max((c * dx + s * dy) * sx, -4.0), 4.0)
            vec[_REL + 1] = min(max((-s * dx + c * dy) * sx, -4.0), 4.0)
            out.append(vec)
        return out


@dataclass(frozen=True)
class RewardWeights:
    """Weights of the shaped per-robot reward; the defaults equal the
    ``[reward]`` section of the server's built-in match configuration."""

    goal: float = 10.0
    close: float = 0.1
    close_scale: float = 1.0
    control: float = 0.5
    opponent_control: float = 0.2


def log_compress(s: float) -> float:
    """``sign(s) * ln(1 + |s|)``: keeps the sign, compresses the size."""
    return math.copysign(math.log1p(abs(s)), s) if s else 0.0


def team_rewards(
    w: RewardWeights,
    after: Optional[Dict[str, Any]],
    goals_for: int,
    goals_against: int,
) -> List[float]:
    """The per-player reward of one tick, from the observation after it.

    ``s = goal + close + control + opponent_control``, reward
    ``sign(s) * ln(1 + |s|)``, the same terms the server's learning crate uses
    (DESIGN.md): every player gets ``+goal`` per goal scored and ``-goal`` per
    goal conceded during the tick; ``close * exp(-d / close_scale)`` for its
    distance ``d`` to the ball; ``control`` if it controls the ball; and
    ``-opponent_control`` while an opponent does. ``after`` is ``None`` for
    the last tick of a match (the server sends ``match_end`` instead of an
    observation), which then carries only the goal term.
    """
    goal = w.goal * (goals_for - goals_against)
    if after is None:
        return [log_compress(goal)] * PLAYERS_PER_TEAM
    opp = -w.opponent_control if after["opponent_control"] else 0.0
    bx, by = after["ball"]["x"], after["ball"]["y"]
    out = []
    for r, ctl in zip(after["own"], after["control"]):
        d = math.hypot(bx - r["x"], by - r["y"])
        s = goal + opp + w.close * math.exp(-d / w.close_scale) + (w.control if ctl else 0.0)
        out.append(log_compress(s))
    return out
