"""The examples and the benchmark run end to end (with tiny budgets)."""

import os
import subprocess
import sys

import pytest

PY = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def run(binary, script, *args, timeout=600):
    env = dict(os.environ, NAOSOCCER_BIN=binary)
    out = subprocess.run(
        [sys.executable, os.path.join(PY, script), *args],
        capture_output=True,
        text=True,
        timeout=timeout,
        env=env,
    )
    assert out.returncode == 0, out.stderr
    return out.stdout


def test_random_agent(binary):
    text = run(binary, "examples/random_agent.py", "--minutes", "0.2", "--seed", "3")
    assert "final score: blue" in text and "ball control" in text


def test_sb3_ppo(binary):
    pytest.importorskip("stable_baselines3")
    pytest.importorskip("naosoccer._native", reason="the native extension is not built (scripts/wheel --in-place)")
    text = run(
        binary,
        "examples/sb3_ppo.py",
        "--timesteps", "1024",
        "--train-minutes", "0.1",
        "--eval-minutes", "0.1",
        "--eval-matches", "1",
    )
    assert "trained 1024 robot steps" in text and "PPO" in text and "vs scripted" in text


def test_bench_env(binary):
    text = run(binary, "bench_env.py", "--minutes", "0.2", "--matches", "1")
    assert "team steps/s" in text


def test_bench_env_vector(binary):
    pytest.importorskip("naosoccer._native", reason="the native extension is not built (scripts/wheel --in-place)")
    text = run(binary, "bench_env.py", "--vector", "--num-matches", "2", "--seconds", "0.5", "--minutes", "0.1")
    assert "match ticks/s" in text and "matches ended" in text


def test_cleanrl_ppo(binary, tmp_path):
    pytest.importorskip("torch")
    pytest.importorskip("naosoccer._native", reason="the native extension is not built (scripts/wheel --in-place)")
    out = tmp_path / "team"
    text = run(
        binary,
        "examples/cleanrl_ppo.py",
        "--seconds", "2",
        "--num-matches", "2",
        "--num-steps", "16",
        "--minutes", "0.1",
        "--out", str(out),
        "--eval-matches", "1",
        "--eval-minutes", "0.2",
        "--eval-against", "random",
    )
    assert "match ticks" in text and "vs random" in text
    # The exported team is in the shipped format: config.json and weights.
    assert (out / "config.json").is_file() and (out / "final.safetensors").is_file()
