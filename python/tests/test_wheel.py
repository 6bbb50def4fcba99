"""The wheel, installed into a fresh virtual environment outside the
checkout, with no ``naosoccer`` on PATH and no ``$NAOSOCCER_BIN``: the
package's own binary is found and runs the servers and evaluations started
from Python, and the in-process vector env plays the binary's match.

The wheel is ``$NAOSOCCER_WHEEL`` when set (scripts/test and
``scripts/wheel --check`` build one and set it); else this test builds one
with scripts/wheel, once per session. It is skipped only when maturin, which
scripts/setup installs (scripts/requirements-dev.txt), is not there. pip
fetches the wheel's dependencies (numpy, gymnasium, pettingzoo) from its
index or cache.
"""

import json
import os
import shutil
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]


def find_maturin():
    for candidate in (os.environ.get("MATURIN"), str(Path(sys.executable).parent / "maturin"),
                      str(REPO / ".venv" / "bin" / "maturin"), shutil.which("maturin")):
        if candidate and os.access(candidate, os.X_OK):
            return candidate
    return None


@pytest.fixture(scope="session")
def wheel():
    given = os.environ.get("NAOSOCCER_WHEEL")
    if given:
        assert os.path.isfile(given), f"$NAOSOCCER_WHEEL names no file: {given}"
        return given
    maturin = find_maturin()
    if maturin is None:
        pytest.skip("maturin is not installed (scripts/setup installs it from scripts/requirements-dev.txt), "
                    "so no wheel can be built; or set NAOSOCCER_WHEEL to a wheel")
    out = subprocess.run([str(REPO / "scripts" / "wheel")], cwd=REPO, env={**os.environ, "MATURIN": maturin},
                         capture_output=True, text=True)
    assert out.returncode == 0, out.stdout + out.stderr
    built = [line.split()[1] for line in out.stdout.splitlines() if line.startswith("[wheel] /")]
    assert built, out.stdout
    return built[-1]


SCRIPT = textwrap.dedent(
    """
    import json, os, subprocess, sys
    import numpy as np
    import naosoccer
    from naosoccer import LocalServer, NaoSoccerParallelEnv, VectorEnv, binary_path
    from naosoccer.evaluation import EvalSpec, play_block

    report = {"package": naosoccer.__file__, "binary": binary_path()}
    with LocalServer() as srv:
        # What the kernel says the child runs, not only what was asked for.
        report["server_binary"] = srv.binary
        report["server_exe"] = os.path.realpath(f"/proc/{srv.proc.pid}/exe")
    env = NaoSoccerParallelEnv(opponent="scripted", minutes=0.1)
    env.reset(seed=3)
    while env.agents:
        _, _, _, _, infos = env.step({a: 0 for a in env.agents})
    report["socket_score"] = infos["blue_0"]["match_end"]["score"]
    env.close()
    vec = VectorEnv(2, opponent="scripted", minutes=0.1, seed=3)
    vec.reset()
    while True:
        _, _, term, _, infos = vec.step(np.full((2, 4), 4))
        if term.all():
            break
    report["vector_hash"] = infos["final_info"]["state_hash"][0]
    cli = subprocess.run([binary_path(), "match", "--seed", "3", "--minutes", "0.1", "--blue", "idle",
                          "--red", "scripted", "--json"], check=True, capture_output=True, text=True)
    report["cli_hash"] = json.loads(cli.stdout)["state_hash"]
    block = play_block(EvalSpec(blue="random", red="scripted", matches=2, minutes=0.1), 0, 2)
    report["eval_matches"] = len(json.loads(block.text)["results"])
    print(json.dumps(report))
    """
)


def test_the_wheel_plays_in_a_fresh_venv(wheel, tmp_path):
    venv = tmp_path / "venv"
    subprocess.run([sys.executable, "-m", "venv", str(venv)], check=True)
    py = str(venv / "bin" / "python")
    subprocess.run([py, "-m", "pip", "install", "-q", "--disable-pip-version-check", wheel], check=True)
    env = {k: v for k, v in os.environ.items() if k not in ("NAOSOCCER_BIN", "PYTHONPATH", "VIRTUAL_ENV")}
    env["PATH"] = "/usr/bin:/bin"
    out = subprocess.run([py, "-c", SCRIPT], cwd=tmp_path, env=env, capture_output=True, text=True, timeout=900)
    assert out.returncode == 0, out.stderr
    report = json.loads(out.stdout.strip().splitlines()[-1])
    site = str(venv)
    assert report["package"].startswith(site), report
    assert report["binary"].startswith(site) and report["binary"].endswith("naosoccer/bin/naosoccer"), report
    assert report["server_binary"] == report["binary"]
    assert report["server_exe"] == os.path.realpath(report["binary"])
    assert set(report["socket_score"]) == {"blue", "red"}
    assert report["vector_hash"] == report["cli_hash"]
    assert report["eval_matches"] == 2
