"""Evaluations played one match at a time and merged (naosoccer.evaluation)
equal `naosoccer eval --json`, text for text; league standings and ratings
(naosoccer.league). No Ray needed."""

import json
import math
import os
import subprocess

import numpy as np
import pytest

from naosoccer.evaluation import (
    EvalSpec,
    _float_text,
    dumps,
    eval_document,
    eval_match_seed,
    format_table,
    legacy_match_seed,
    play_match,
    shifted_seed,
    wilson,
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


def with_wall(text, wall):
    doc = json.loads(text)
    doc["wall_seconds"] = wall
    return doc


def test_shifted_seed_makes_match_i_the_first_match():
    # The values naosoccer eval derives (crates/policy/src/eval.rs), first
    # from the formula, then through the shift the tasks rely on.
    for seed in (0, 1, 7, 2**63, 2**64 - 1):
        for i in (0, 1, 2, 15, 999):
            assert eval_match_seed(seed, i) >> 63 == 1
            assert eval_match_seed(shifted_seed(seed, i), 0) == eval_match_seed(seed, i)
            assert legacy_match_seed(shifted_seed(seed, i, legacy=True), 0) == legacy_match_seed(seed, i)
            assert 0 <= shifted_seed(seed, i) < 2**64
    assert len({eval_match_seed(3, i) for i in range(200)}) == 200


@pytest.mark.parametrize(
    "spec",
    [
        EvalSpec("scripted", "random", matches=5, seed=11, both_sides=True, minutes=0.5),
        EvalSpec("ppo:assets/policies/ppo-team-seed1", "scripted", matches=3, seed=2**64 - 1,
                 legacy_seeds=True, minutes=0.3),
    ],
    ids=["both-sides", "ppo-legacy-seeds"],
)
def test_matches_played_alone_merge_into_the_binarys_json(binary, spec):
    want = binary_eval(binary, spec).strip()
    outcomes = [play_match(spec, i, binary=binary, cwd=REPO) for i in range(spec.matches)]
    got = eval_document(spec, list(reversed(outcomes)), json.loads(want)["wall_seconds"])
    # The same text: same keys, same floats to the last bit, NaN as null.
    assert dumps(got) == want
    table = binary_eval(binary, spec, json_out=False)
    # The table but for the wall-clock time on its last line.
    assert format_table(got).splitlines()[:-1] == table.splitlines()[:-1]


def test_one_match_has_no_interval(binary):
    spec = EvalSpec("idle", "random", matches=1, seed=4, minutes=0.2)
    want = binary_eval(binary, spec).strip()
    got = eval_document(spec, [play_match(spec, 0, binary=binary, cwd=REPO)], json.loads(want)["wall_seconds"])
    assert '"ci95":null' in want
    assert dumps(got) == want


def test_float_text_follows_serde_json():
    for x, text in [(1e16, "1e16"), (1.5e-7, "1.5e-7"), (1e-5, "0.00001"), (1.25e-5, "0.0000125"),
                    (123.0, "123.0"), (0.1, "0.1"), (-2.5e20, "-2.5e20"), (1e15, "1000000000000000.0")]:
        assert _float_text(x) == text
        assert float(text) == x
    assert _float_text(math.nan) == "null"


def test_wilson_matches_hand_computed_values():
    # The binary's own test values (crates/policy/src/eval.rs).
    for k, n, low, high in [(0, 10, 0.0, 0.277540), (5, 10, 0.236590, 0.763410), (80, 100, 0.711169, 0.866634)]:
        _, lo, hi = wilson(k, n)
        assert abs(lo - low) < 1e-5 and abs(hi - high) < 1e-5


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
