"""Ray started locally (no RAY_ADDRESS): `python -m naosoccer.ray eval` and
the RLlib example's smoke run (two PPO iterations on tiny batches, one env
runner with its own server)."""

import json
import os
import re
import subprocess
import sys

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
    # No usage stats, and no token written into the home directory.
    env.update(NAOSOCCER_BIN=binary, PYTHONPATH=PYTHON_DIR, RAY_USAGE_STATS_ENABLED="0", RAY_AUTH_MODE="disabled")
    out = subprocess.run([sys.executable, *args], cwd=REPO, env=env, capture_output=True, text=True, timeout=timeout)
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
    text = run(binary, [
        os.path.join(PYTHON_DIR, "examples", "rllib_ppo.py"),
        "--env-runners", "1", "--iterations", "2", "--train-batch", "128", "--minibatch", "64",
        "--epochs", "1", "--minutes", "0.2",
    ])
    steps = [int(n) for n in re.findall(r"^iteration \d+: (\d+) env steps", text, re.M)]
    assert len(steps) == 2 and 128 <= steps[0] < steps[1], text
    assert f"trained {steps[1]} env steps with RLlib PPO" in text
