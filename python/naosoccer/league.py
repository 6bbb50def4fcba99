"""League standings from round-robin evaluations: wins, draws and losses,
goals, and a Bradley–Terry rating on the Elo scale with a 95% interval.

A league of N teams plays every pairing ``(i, j)``, ``i < j`` in the order
given, as ``naosoccer eval --blue TEAM_i --red TEAM_j --matches M --seed S
--both-sides``: every pairing plays the same match seeds, half of its matches
with the sides swapped. :func:`standings` needs only those evaluations'
``--json`` objects, so a league played on a cluster and one pieced together
from single-machine evaluations give the same table.

The rating is the maximum of the Bradley–Terry posterior: a team's strength
``theta`` and P(i beats j) = 1 / (1 + exp(theta_j - theta_i)); a draw counts
as half a win for each side, and every pairing gets one virtual draw (a weak
prior that keeps a team that won every match at a finite rating). Ratings are
``400 log10(e) theta``, the Elo scale (400 points: 10 to 1 odds), centred on
a mean of 0. The interval is ±1.96 standard errors from the curvature of the
log posterior at its maximum (the Laplace approximation).
"""

from __future__ import annotations

import math
from typing import Any, Dict, List, Sequence, Tuple

import numpy as np

#: Elo points per unit of Bradley–Terry log-strength.
ELO_PER_NAT = 400.0 / math.log(10.0)
#: Virtual draws added to every pairing (the prior).
PRIOR_DRAWS = 1.0


def pairings(n: int) -> List[Tuple[int, int]]:
    """The round robin's pairings: (i, j), i < j, i playing ``--blue``."""
    return [(i, j) for i in range(n) for j in range(i + 1, n)]


def bradley_terry(scores: np.ndarray, prior_draws: float = PRIOR_DRAWS) -> Tuple[np.ndarray, np.ndarray]:
    """Log-strengths (centred) and their standard errors.

    ``scores[i, j]`` is what ``i`` scored against ``j`` (a win 1, a draw
    1/2). Every pair that met gets ``prior_draws`` virtual draws.
    """
    n = scores.shape[0]
    met = (scores + scores.T) > 0
    w = scores + np.where(met, prior_draws / 2.0, 0.0)
    games = w + w.T
    theta = np.zeros(n)
    info = np.zeros((n, n))
    for _ in range(200):
        p = 1.0 / (1.0 + np.exp(theta[None, :] - theta[:, None]))
        grad = (w - games * p).sum(axis=1)
        c = games * p * p.T
        info = np.diag(c.sum(axis=1)) - c
        step = np.linalg.pinv(info) @ grad
        theta = theta + step
        theta -= theta.mean()
        if np.max(np.abs(step)) < 1e-12:
            break
    p = 1.0 / (1.0 + np.exp(theta[None, :] - theta[:, None]))
    c = games * p * p.T
    info = np.diag(c.sum(axis=1)) - c
    cov = np.linalg.pinv(info)
    return theta, np.sqrt(np.clip(np.diag(cov), 0.0, None))


def standings(teams: Sequence[str], evals: Sequence[Dict[str, Any]]) -> List[Dict[str, Any]]:
    """The league table, best first, from one ``naosoccer eval --json``
    object per pairing (in :func:`pairings` order)."""
    n = len(teams)
    pairs = pairings(n)
    if len(evals) != len(pairs):
        raise ValueError(f"{n} teams play {len(pairs)} pairings, got {len(evals)} evaluations")
    rows = [
        {"team": t, "matches": 0, "wins": 0, "draws": 0, "losses": 0, "goals_for": 0, "goals_against": 0}
        for t in teams
    ]
    scores = np.zeros((n, n))
    for (i, j), doc in zip(pairs, evals):
        if (doc["blue"]["name"], doc["red"]["name"]) != (teams[i], teams[j]):
            raise ValueError(f"evaluation of {doc['blue']['name']} v {doc['red']['name']} is not pairing {teams[i]} v {teams[j]}")
        for gi, gj in doc["scores"]:
            for k, own, opp in ((i, gi, gj), (j, gj, gi)):
                r = rows[k]
                r["matches"] += 1
                r["goals_for"] += own
                r["goals_against"] += opp
                r["wins" if own > opp else "draws" if own == opp else "losses"] += 1
            scores[i, j] += 1.0 if gi > gj else 0.5 if gi == gj else 0.0
            scores[j, i] += 1.0 if gj > gi else 0.5 if gi == gj else 0.0
    theta, se = bradley_terry(scores)
    for k, r in enumerate(rows):
        r["goal_difference"] = r["goals_for"] - r["goals_against"]
        r["points"] = 3 * r["wins"] + r["draws"]
        rating = float(theta[k] * ELO_PER_NAT)
        half = float(1.96 * se[k] * ELO_PER_NAT)
        r["rating"] = rating
        r["rating_low"] = rating - half
        r["rating_high"] = rating + half
    order = sorted(range(n), key=lambda k: (-round(rows[k]["rating"], 6), -rows[k]["goal_difference"], k))
    out = []
    for rank, k in enumerate(order, 1):
        out.append({"rank": rank, **rows[k]})
    return out


def league_document(
    teams: Sequence[str],
    matches: int,
    seed: int,
    evals: Sequence[Dict[str, Any]],
    wall_seconds: float,
) -> Dict[str, Any]:
    """The league's JSON: its settings, the standings and every pairing's
    evaluation (``naosoccer eval --json`` without ``wall_seconds``)."""
    return {
        "teams": list(teams),
        "matches_per_pairing": matches,
        "seed": seed,
        "both_sides": True,
        "minutes": evals[0]["minutes"] if evals else None,
        "rating": {
            "model": "bradley-terry",
            "scale": "elo",
            "prior_draws_per_pairing": PRIOR_DRAWS,
            "interval": "95% (1.96 standard errors, Laplace)",
        },
        "standings": standings(teams, evals),
        "pairings": [{k: v for k, v in doc.items() if k != "wall_seconds"} for doc in evals],
        "wall_seconds": wall_seconds,
    }


def _signed(x: float) -> str:
    return f"{x:+.0f}" if round(x) != 0 else "0"


def markdown(doc: Dict[str, Any]) -> str:
    """The standings and the pairings' results as markdown tables."""
    lines = [
        f"League of {len(doc['teams'])} teams: round robin, {doc['matches_per_pairing']} matches a pairing "
        f"(every other one with the sides swapped), seed {doc['seed']}, {doc['minutes']:.1f} min matches.",
        "",
        "| # | team | matches | W | D | L | goals | goal diff. | points | rating (Elo) | 95% interval |",
        "|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|---|",
    ]
    for r in doc["standings"]:
        lines.append(
            f"| {r['rank']} | `{r['team']}` | {r['matches']} | {r['wins']} | {r['draws']} | {r['losses']} "
            f"| {r['goals_for']}:{r['goals_against']} | {r['goal_difference']:+d} | {r['points']} "
            f"| {_signed(r['rating'])} | [{_signed(r['rating_low'])}, {_signed(r['rating_high'])}] |"
        )
    lines += [
        "",
        "| pairing | W/D/L of the first | goals |",
        "|---|---:|---:|",
    ]
    for p in doc["pairings"]:
        sc = p["scores"]
        w = sum(1 for a, b in sc if a > b)
        d = sum(1 for a, b in sc if a == b)
        gf, ga = sum(a for a, _ in sc), sum(b for _, b in sc)
        lines.append(f"| `{p['blue']['name']}` v `{p['red']['name']}` | {w}/{d}/{len(sc) - w - d} | {gf}:{ga} |")
    lines += [
        "",
        "Ratings: Bradley–Terry on the Elo scale (mean 0), a draw half a win, one virtual draw "
        "per pairing as the prior; intervals ±1.96 standard errors.",
    ]
    return "\n".join(lines) + "\n"
