"""Evaluations played in blocks and merged by the binary
(naosoccer.evaluation) equal `naosoccer eval`, text for text; league
standings and ratings (naosoccer.league). No Ray needed."""

import json
import math
import os
import re
import subprocess

import numpy as np
import pytest

from naosoccer.evaluation import (
    MAX_BLOCK,
    EvalSpec,
    blocks,
    default_block,
    evaluate,
    merge_blocks,
    play_block,
)
from naosoccer.league import ELO_PER_NAT, bradley_terry, league_document, markdown, standings

REPO = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def binary_eval(binary, spec, *, json_out=True):
    cmd = [binary, "eval", "--blue", spec.blue, "--red", spec.red, "--matches", str(spec.matches),
           "--seed", str(spec.seed)]
    if spec.minutes is not None:
        cmd += ["--minutes", str(spec.minutes)]
    if spec.config is not None:
        cmd += ["--config", spec.config]
    if spec.both_sides:
        cmd.append("--both-sides")
    if spec.legacy_seeds:
        cmd.append("--legacy-seeds")
    if json_out:
        cmd.append("--json")
    out = subprocess.run(cmd, cwd=REPO, capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr
    return out.stdout


def without_wall(text):
    """The text but for the wall-clock time: the JSON's wall_seconds, or the
    table's last line."""
    if text.startswith("{"):
        return re.sub(r'"wall_seconds":[^,}]+', '"wall_seconds":0', text)
    return text.splitlines()[:-1]


def test_blocks_cut_the_matches_in_order():
    assert blocks(6, 4) == [(0, 4), (4, 2)]
    assert blocks(5, 1) == [(i, 1) for i in range(5)]
    assert blocks(3, 10) == [(0, 3)]
    with pytest.raises(ValueError):
        blocks(3, 0)
    # About two blocks a CPU, at most MAX_BLOCK matches.
    assert default_block(16, 2) == 4
    assert default_block(1, 8) == 1
    assert default_block(10_000, 2) == MAX_BLOCK


@pytest.mark.parametrize(
    "spec",
    [
        EvalSpec("scripted", "random", matches=5, seed=11, both_sides=True, minutes=0.5),
        EvalSpec("ppo:assets/policies/ppo-team-seed1", "scripted", matches=3, seed=2**64 - 1,
                 legacy_seeds=True, minutes=0.3),
    ],
    ids=["both-sides", "ppo-legacy-seeds"],
)
def test_blocks_merge_into_the_binarys_output(binary, spec):
    want = binary_eval(binary, spec)
    # Blocks of 2, handed to the merge out of order.
    played = [play_block(spec, f, n, binary=binary, cwd=REPO) for f, n in blocks(spec.matches, 2)]
    got = merge_blocks(list(reversed(played)), binary=binary)
    # The same text: same keys, same floats to the last bit, NaN as null.
    assert without_wall(got) == without_wall(want)
    # wall_seconds is the sum of the blocks'.
    walls = [json.loads(b.text)["wall_seconds"] for b in played]
    assert json.loads(got)["wall_seconds"] == pytest.approx(sum(walls))
    table = merge_blocks(played, binary=binary, json_out=False)
    assert without_wall(table) == without_wall(binary_eval(binary, spec, json_out=False))
    assert evaluate(spec, block=2, binary=binary, cwd=REPO)["results"] == json.loads(want)["results"]


def test_one_match_has_no_interval(binary):
    spec = EvalSpec("idle", "random", matches=1, seed=4, minutes=0.2)
    want = binary_eval(binary, spec)
    got = merge_blocks([play_block(spec, 0, 1, binary=binary, cwd=REPO)], binary=binary)
    assert '"ci95":null' in want
    assert without_wall(got) == without_wall(want)


def test_merge_refuses_a_gap(binary):
    spec = EvalSpec("idle", "random", matches=4, seed=4, minutes=0.2)
    played = [play_block(spec, f, 1, binary=binary, cwd=REPO) for f in (0, 2)]
    with pytest.raises(RuntimeError, match="match 1 is missing"):
        merge_blocks(played, binary=binary)


def test_bradley_terry_two_teams_is_the_log_odds():
    # 7 wins, 1 draw, 2 losses: 7.5 v 2.5, plus the virtual draw: 8 v 3.
    scores = np.array([[0.0, 7.5], [2.5, 0.0]])
    theta, se = bradley_terry(scores)
    assert theta[0] - theta[1] == pytest.approx(math.log(8.0 / 3.0), abs=1e-9)
    assert theta.sum() == pytest.approx(0.0, abs=1e-12)
    # Fisher information of the difference: n p (1 - p), n = 11.
    p = 8.0 / 11.0
    assert 2 * se[0] == pytest.approx(1.0 / math.sqrt(11 * p * (1 - p)), rel=1e-9)


def fake_eval(blue, red, scores):
    return {"blue": {"name": blue}, "red": {"name": red}, "scores": scores, "minutes": 1.0}


def test_standings_rank_by_rating_and_count_every_match():
    teams = ["a", "b", "c"]
    evals = [
        fake_eval("a", "b", [[2, 0], [1, 1]]),
        fake_eval("a", "c", [[3, 0], [1, 0]]),
        fake_eval("b", "c", [[0, 0], [2, 1]]),
    ]
    table = standings(teams, evals)
    assert [r["team"] for r in table] == ["a", "b", "c"]
    a, b, c = table
    assert (a["wins"], a["draws"], a["losses"], a["goals_for"], a["goals_against"]) == (3, 1, 0, 7, 1)
    assert (b["wins"], b["draws"], b["losses"], b["goal_difference"]) == (1, 2, 1, -1)
    assert (c["wins"], c["draws"], c["losses"], c["points"]) == (0, 1, 3, 1)
    assert sum(r["rating"] for r in table) == pytest.approx(0.0, abs=1e-9)
    for r in table:
        assert r["rating_low"] < r["rating"] < r["rating_high"]
    # A team that won every match still has a finite rating (the prior).
    sweep = standings(["x", "y"], [fake_eval("x", "y", [[1, 0]] * 6)])
    assert math.isfinite(sweep[0]["rating"]) and sweep[0]["rating"] > 0
    assert sweep[0]["rating"] - sweep[1]["rating"] == pytest.approx(ELO_PER_NAT * math.log(6.5 / 0.5))
    with pytest.raises(ValueError):
        standings(teams, evals[:2])
    with pytest.raises(ValueError):
        standings(teams, [evals[1], evals[0], evals[2]])
    doc = league_document(teams, 2, 0, [dict(e, wall_seconds=1.0) for e in evals], 1.0)
    md = markdown(doc)
    for t in teams:
        assert f"`{t}`" in md
