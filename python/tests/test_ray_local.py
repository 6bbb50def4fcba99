"""Ray started locally (no RAY_ADDRESS): `python -m naosoccer.ray eval` and
the RLlib example's smoke run (two PPO iterations on tiny batches, one env
runner stepping its own match in process, with the native extension)."""

import json
import os
import re
import shutil
import subprocess
import sys
import tempfile

import pytest

pytest.importorskip(
    "ray", reason="Ray is not installed: pip install './python[ray]' (scripts/setup installs it)"
)
pytest.importorskip(
    "ray.rllib", reason="RLlib is not installed: pip install './python[ray]' (scripts/setup installs it)"
)

REPO = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
PYTHON_DIR = os.path.join(REPO, "python")


def run(binary, args, timeout=600):
    env = {k: v for k, v in os.environ.items() if k not in ("RAY_ADDRESS", "PYTHONPATH")}
    # No usage stats, no token written into the home directory, and the
    # local Ray's session files in a directory of the test's own (short:
    # Ray's socket paths must fit in 107 bytes).
    temp_dir = tempfile.mkdtemp(prefix="nsray-")
    env.update(
        NAOSOCCER_BIN=binary, PYTHONPATH=PYTHON_DIR, RAY_USAGE_STATS_ENABLED="0", RAY_AUTH_MODE="disabled",
        RAY_TMPDIR=temp_dir,
    )
    try:
        out = subprocess.run(
            [sys.executable, *args], cwd=REPO, env=env, capture_output=True, text=True, timeout=timeout
        )
    finally:
        shutil.rmtree(temp_dir, ignore_errors=True)
    assert out.returncode == 0, out.stderr[-4000:]
    return out.stdout


def test_eval_starts_a_local_ray_without_an_address(binary):
    args = ["--blue", "random", "--red", "scripted", "--matches", "3", "--seed", "8", "--minutes", "0.2"]
    got = json.loads(run(binary, ["-m", "naosoccer.ray", "eval", *args, "--num-cpus", "1", "--json"]))
    want = subprocess.run([binary, "eval", *args, "--json"], capture_output=True, text=True, check=True)
    want = json.loads(want.stdout)
    got.pop("wall_seconds")
    want.pop("wall_seconds")
    assert got == want


def test_rllib_ppo_example_trains_two_iterations(binary):
    pytest.importorskip("naosoccer._native", reason="the native extension is not built (scripts/wheel --in-place)")
    text = run(binary, [
        os.path.join(PYTHON_DIR, "examples", "rllib_ppo.py"),
        "--env-runners", "1", "--iterations", "2", "--train-batch", "128", "--minibatch", "64",
        "--epochs", "1", "--minutes", "0.2",
    ])
    steps = [int(n) for n in re.findall(r"^iteration \d+: (\d+) env steps", text, re.M)]
    assert len(steps) == 2 and 128 <= steps[0] < steps[1], text
    assert f"trained {steps[1]} env steps with RLlib PPO" in text


class _Context(dict):
    """RLlib's EnvContext as make_env sees it: env_config plus the runner."""

    worker_index = 2


def test_rllib_env_runners_play_disjoint_seeds():
    pytest.importorskip("naosoccer._native", reason="the native extension is not built (scripts/wheel --in-place)")
    from naosoccer.ray.rllib import SEED_STRIDE, make_env

    env = make_env(_Context(seed=3, minutes=0.1))
    try:
        # Built by runner 2 of seed 3: the wrapper's own first match (RLlib's
        # wrapper resets once on construction) has seed (3 + 2) * STRIDE.
        assert env.par_env.match_seed == 5 * SEED_STRIDE
        # RLlib then resets runner 2 with seed 3 + 2; the next match, unseeded, follows.
        env.reset(seed=5)
        assert env.par_env.match_seed == 5 * SEED_STRIDE
        env.reset()
        assert env.par_env.match_seed == 5 * SEED_STRIDE + 1
        assert set(env.possible_agents) == {f"blue_{p}" for p in range(4)}
        # The paper's five actions, unmasked: RLlib's default module reads no masks.
        assert env.par_env.num_actions == 5
    finally:
        env.close()
