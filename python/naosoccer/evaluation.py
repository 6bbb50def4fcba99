"""Evaluations split into single matches and merged again: what
``naosoccer eval`` computes, rebuilt from matches played one at a time.

``naosoccer eval --seed S --matches N`` plays matches ``0..N``; match ``i``
has the seed ``eval_match_seed(S, i)`` (crates/policy/src/eval.rs). The
derivation adds ``(i + 1)`` golden-ratio steps to ``S ^ C`` before mixing, so
``eval_match_seed(S, i) == eval_match_seed(shifted_seed(S, i), 0)``: match
``i`` of an evaluation is match 0 of ``naosoccer eval --seed
shifted_seed(S, i) --matches 1``, on any machine with the same build. With
``--both-sides`` the odd matches swap the sides, which is the same match with
the two teams named the other way round. Each match runs in its own
process; :func:`summarise` then redoes the binary's arithmetic (Student t
intervals, Wilson interval, same order of float operations), so the merged
JSON equals ``naosoccer eval --json`` key for key and bit for bit, but for
``wall_seconds``.

Nothing here needs Ray: :mod:`naosoccer.ray` sends :func:`play_match` to the
nodes of a cluster.
"""

from __future__ import annotations

import json
import math
import os
import subprocess
from dataclasses import dataclass
from typing import Any, Dict, List, Optional, Sequence, Tuple

from .server import BIN_ENV, find_binary

MASK64 = (1 << 64) - 1
_GOLDEN = 0x9E3779B97F4A7C15
_EVAL_STREAM = 0x5EEDE7A100000000
EVAL_SEED_BIT = 1 << 63


def _mix(z: int) -> int:
    z = ((z ^ (z >> 30)) * 0xBF58476D1CE4E5B9) & MASK64
    z = ((z ^ (z >> 27)) * 0x94D049BB133111EB) & MASK64
    return z ^ (z >> 31)


def eval_match_seed(seed: int, index: int) -> int:
    """The seed of evaluation match ``index`` under ``--seed seed``, as
    ``naosoccer eval`` derives it."""
    return _mix(((seed ^ _EVAL_STREAM) + (index + 1) * _GOLDEN) & MASK64) | EVAL_SEED_BIT


def legacy_match_seed(seed: int, index: int) -> int:
    """The seed of match ``index`` under ``--seed seed --legacy-seeds``."""
    return _mix((seed ^ ((index * _GOLDEN) & MASK64)) & MASK64)


def shifted_seed(seed: int, index: int, legacy: bool = False) -> int:
    """The ``--seed`` whose match 0 is match ``index`` of ``--seed seed``."""
    if legacy:
        return (seed ^ ((index * _GOLDEN) & MASK64)) & MASK64
    return (((seed ^ _EVAL_STREAM) + index * _GOLDEN) & MASK64) ^ _EVAL_STREAM


@dataclass(frozen=True)
class EvalSpec:
    """One evaluation: the options of ``naosoccer eval``."""

    blue: str
    red: str = "scripted"
    matches: int = 50
    seed: int = 0
    both_sides: bool = False
    legacy_seeds: bool = False
    config: Optional[str] = None
    minutes: Optional[float] = None

    def swapped(self, index: int) -> bool:
        return self.both_sides and index % 2 == 1

    def check(self) -> None:
        if self.matches < 1:
            raise ValueError("--matches must be at least 1")
        if not 0 <= self.seed <= MASK64:
            raise ValueError(f"--seed must be in 0..2^64-1, got {self.seed}")
        if self.minutes is not None and not self.minutes > 0:
            raise ValueError(f"--minutes must be positive, got {self.minutes}")


@dataclass(frozen=True)
class MatchOutcome:
    """One match of an evaluation, each pair as (first team, second team):
    the first is ``--blue``, whichever colour it played."""

    index: int
    swapped: bool
    goals: Tuple[int, int]
    control_rate_percent: Tuple[float, float]
    passes: Tuple[int, int]
    shots: Tuple[int, int]
    #: The match length the binary reports (its configuration's, as f32).
    minutes: float
    #: Where it was played (a Ray node id, or "" when played locally).
    node: str = ""


def match_command(binary: str, spec: EvalSpec, index: int) -> List[str]:
    """The ``naosoccer eval`` command line that plays match ``index`` of
    ``spec`` alone (the two teams exchanged when the match swaps sides)."""
    first, second = (spec.red, spec.blue) if spec.swapped(index) else (spec.blue, spec.red)
    cmd = [
        binary, "eval", "--blue", first, "--red", second, "--matches", "1",
        "--seed", str(shifted_seed(spec.seed, index, spec.legacy_seeds)),
        "--threads", "1", "--json",
    ]
    if spec.legacy_seeds:
        cmd.append("--legacy-seeds")
    if spec.config is not None:
        cmd += ["--config", spec.config]
    if spec.minutes is not None:
        cmd += ["--minutes", repr(float(spec.minutes))]
    return cmd


def resolve_binary(base: str, binary: Optional[str] = None) -> str:
    """The binary as :func:`naosoccer.find_binary` finds it, with a relative
    ``binary`` or ``$NAOSOCCER_BIN`` taken relative to ``base``."""
    explicit = binary or os.environ.get(BIN_ENV)
    if explicit and not os.path.isabs(explicit):
        explicit = os.path.join(base, explicit)
    return find_binary(explicit)


def play_match(
    spec: EvalSpec,
    index: int,
    *,
    binary: Optional[str] = None,
    cwd: Optional[str] = None,
    node: str = "",
) -> MatchOutcome:
    """Plays match ``index`` of ``spec`` in a ``naosoccer eval`` child
    process. Relative team directories, ``--config`` and ``binary`` are
    taken relative to ``cwd`` when that directory exists here, else to the
    current directory."""
    base = cwd if cwd and os.path.isdir(cwd) else os.getcwd()
    exe = resolve_binary(base, binary)
    cmd = match_command(exe, spec, index)
    out = subprocess.run(cmd, cwd=base, stdin=subprocess.DEVNULL, capture_output=True, text=True)
    if out.returncode != 0:
        raise RuntimeError(f"{' '.join(cmd)} failed (exit {out.returncode}): {out.stderr.strip()[-2000:]}")
    return outcome_from_json(json.loads(out.stdout), index, spec.swapped(index), node)


def outcome_from_json(doc: Dict[str, Any], index: int, swapped: bool, node: str = "") -> MatchOutcome:
    """A match from the ``--json`` of a one-match ``naosoccer eval``: the
    means over one match are the match's own values."""
    if doc["matches"] != 1 or len(doc["scores"]) != 1:
        raise ValueError("expected the JSON of a one-match evaluation")
    # The child played the first team as blue unless the sides swap.
    a, b = (doc["red"], doc["blue"]) if swapped else (doc["blue"], doc["red"])
    pair = lambda key, conv: (conv(a[key]["mean"]), conv(b[key]["mean"]))  # noqa: E731
    score = doc["scores"][0]
    goals = (score[1], score[0]) if swapped else (score[0], score[1])
    return MatchOutcome(
        index=index,
        swapped=swapped,
        goals=(int(goals[0]), int(goals[1])),
        control_rate_percent=pair("control_rate_percent", float),
        passes=pair("passes", lambda x: int(round(x))),
        shots=pair("shots", lambda x: int(round(x))),
        minutes=float(doc["minutes"]),
        node=node,
    )


# ---------------------------------------------------------------- statistics
# The binary's arithmetic (crates/policy/src/eval.rs), operation for operation.

_T95 = (
    12.706, 4.303, 3.182, 2.776, 2.571, 2.447, 2.365, 2.306, 2.262, 2.228, 2.201, 2.179, 2.160,
    2.145, 2.131, 2.120, 2.110, 2.101, 2.093, 2.086, 2.080, 2.074, 2.069, 2.064, 2.060, 2.056,
    2.052, 2.048, 2.045, 2.042,
)


def t95(df: int) -> float:
    """The two-sided 95% Student t quantile for ``df`` degrees of freedom."""
    if df == 0:
        return math.nan
    if df <= 30:
        return _T95[df - 1]
    if df <= 60:
        return 2.000 + (2.042 - 2.000) * float(60 - df) / 30.0
    if df <= 120:
        return 1.980 + (2.000 - 1.980) * float(120 - df) / 60.0
    return 1.96


def estimate(xs: Sequence[float]) -> Tuple[float, float]:
    """(mean, 95% half-width) over ``xs``; NaN where undefined."""
    n = len(xs)
    if n == 0:
        return math.nan, math.nan
    total = 0.0
    for x in xs:  # in order, uncompensated: Python's sum() is not
        total += x
    mean = total / n
    if n == 1:
        return mean, math.nan
    sq = 0.0
    for x in xs:
        d = x - mean
        sq += d * d
    var = sq / (n - 1)
    return mean, t95(n - 1) * math.sqrt(var / n)


def wilson(successes: int, n: int) -> Tuple[float, float, float]:
    """(rate, low, high): the Wilson score 95% interval (z = 1.96)."""
    if n == 0:
        return math.nan, math.nan, math.nan
    z = 1.96
    nf = float(n)
    p = successes / nf
    denom = 1.0 + z * z / nf
    centre = (p + z * z / (2.0 * nf)) / denom
    half = z * math.sqrt(p * (1.0 - p) / nf + z * z / (4.0 * nf * nf)) / denom
    return p, min(max(centre - half, 0.0), p), min(max(centre + half, p), 1.0)


def _record(wins: int, draws: int, losses: int) -> Dict[str, int]:
    return {"wins": wins, "draws": draws, "losses": losses}


def summarise(outcomes: Sequence[MatchOutcome], first_name: str, second_name: str) -> List[Dict[str, Any]]:
    """Each team's row, as ``naosoccer eval --json`` writes ``blue`` and ``red``."""
    rows = []
    for k, name in ((0, first_name), (1, second_name)):
        rec = {"blue": [0, 0, 0], "red": [0, 0, 0]}
        for m in outcomes:
            colour = "red" if (k == 0) == m.swapped else "blue"
            own, opp = m.goals[k], m.goals[1 - k]
            rec[colour][0 if own > opp else 1 if own == opp else 2] += 1
        wins = rec["blue"][0] + rec["red"][0]
        rate, low, high = wilson(wins, len(outcomes))

        def est(xs: Sequence[float]) -> Dict[str, float]:
            mean, ci = estimate(xs)
            return {"mean": mean, "ci95": ci}

        rows.append({
            "name": name,
            "goals": est([float(m.goals[k]) for m in outcomes]),
            "control_rate_percent": est([m.control_rate_percent[k] for m in outcomes]),
            "passes": est([float(m.passes[k]) for m in outcomes]),
            "shots": est([float(m.shots[k]) for m in outcomes]),
            "wins": wins,
            "draws": rec["blue"][1] + rec["red"][1],
            "losses": rec["blue"][2] + rec["red"][2],
            "win_rate": {"rate": rate, "low": low, "high": high},
            "as_blue": _record(*rec["blue"]),
            "as_red": _record(*rec["red"]),
        })
    return rows


def eval_document(spec: EvalSpec, outcomes: Sequence[MatchOutcome], wall_seconds: float) -> Dict[str, Any]:
    """The object ``naosoccer eval --json`` prints for ``spec``, from its
    matches in index order."""
    outcomes = sorted(outcomes, key=lambda m: m.index)
    if [m.index for m in outcomes] != list(range(spec.matches)):
        raise ValueError("an evaluation needs every match exactly once")
    blue, red = summarise(outcomes, spec.blue, spec.red)
    return {
        "matches": spec.matches,
        "seed": spec.seed,
        "minutes": outcomes[0].minutes,
        "both_sides": spec.both_sides,
        "seed_scheme": "legacy" if spec.legacy_seeds else "eval",
        "blue": blue,
        "red": red,
        "scores": [[m.goals[0], m.goals[1]] for m in outcomes],
        "swapped": [m.swapped for m in outcomes],
        "wall_seconds": wall_seconds,
    }


def format_table(doc: Dict[str, Any]) -> str:
    """The table ``naosoccer eval`` prints without ``--json``."""
    rows = [doc["blue"], doc["red"]]
    both = any(
        sum(r["as_red"].values()) > 0 and sum(r["as_blue"].values()) > 0 for r in rows
    )

    def est(e: Dict[str, float], p: int) -> str:
        if math.isnan(e["ci95"]):
            return f"{e['mean']:.{p}f}"
        return f"{e['mean']:.{p}f} ± {e['ci95']:.{p}f}"

    def rate(r: Dict[str, float]) -> str:
        return f"{100.0 * r['rate']:.1f} [{100.0 * r['low']:.1f}, {100.0 * r['high']:.1f}]"

    s = (
        f"{doc['matches']} matches{', half with the sides swapped' if both else ''}, "
        "mean ± 95% CI; win % with its Wilson 95% interval\n"
        f"{'team':<28} {'average goals':>14} {'ball control %':>18} {'average passes':>16} "
        f"{'average shots':>16} {'W/D/L':>11} {'win %':>20}\n"
    )
    for r in rows:
        s += (
            f"{r['name']:<28} {est(r['goals'], 2):>14} {est(r['control_rate_percent'], 1):>18} "
            f"{est(r['passes'], 2):>16} {est(r['shots'], 2):>16} "
            f"{str(r['wins']) + '/' + str(r['draws']) + '/' + str(r['losses']):>11} "
            f"{rate(r['win_rate']):>20}\n"
        )
    if both:
        for r in rows:
            b, d = r["as_blue"], r["as_red"]
            s += (
                f"{r['name']}: as blue {b['wins']}/{b['draws']}/{b['losses']}, "
                f"as red {d['wins']}/{d['draws']}/{d['losses']}\n"
            )
    s += f"({doc['minutes']:.1f} min matches, {doc['wall_seconds']:.1f} s)\n"
    return s


# ---------------------------------------------------------------- JSON text


def _float_text(x: float) -> str:
    """A float as serde_json writes it: the shortest digits that read back
    (as repr), in ryu's layout (``1e16``, ``1.5e-7``, ``0.00001``)."""
    if not math.isfinite(x):
        return "null"
    r = repr(x)
    if "e" not in r and "inf" not in r:
        return r
    mantissa, exp = r.split("e")
    e = int(exp)
    neg = mantissa.startswith("-")
    digits = mantissa.lstrip("-").replace(".", "")
    digits = digits.rstrip("0") or "0"
    # value = 0.DIGITS * 10^kk
    kk = e + 1
    sign = "-" if neg else ""
    if 0 < kk <= 16:
        if len(digits) <= kk:
            return f"{sign}{digits}{'0' * (kk - len(digits))}.0"
        return f"{sign}{digits[:kk]}.{digits[kk:]}"
    if -5 < kk <= 0:
        return f"{sign}0.{'0' * -kk}{digits}"
    body = digits if len(digits) == 1 else f"{digits[0]}.{digits[1:]}"
    return f"{sign}{body}e{kk - 1}"


def dumps(obj: Any) -> str:
    """JSON text as the binary prints it: keys sorted, no spaces, NaN as null."""
    if isinstance(obj, dict):
        return "{" + ",".join(f"{json.dumps(str(k))}:{dumps(obj[k])}" for k in sorted(obj)) + "}"
    if isinstance(obj, (list, tuple)):
        return "[" + ",".join(dumps(v) for v in obj) + "]"
    if isinstance(obj, bool) or obj is None:
        return json.dumps(obj)
    if isinstance(obj, float):
        return _float_text(obj)
    if isinstance(obj, int):
        return str(obj)
    return json.dumps(obj)
