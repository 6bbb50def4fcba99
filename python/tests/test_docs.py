"""Every ```python block of docs/PYTHON.md, run as written from the
repository root (the examples name assets/ paths) with this tree's package.

The block that connects to "a running server" gets one: a private server's
address and tokens in the environment variables it reads. The blocks that
use the in-process envs (``VectorEnv``, ``parallel_env``, ``env``) need the
native extension (scripts/wheel --in-place, as scripts/test does); without it
they are skipped and say so. The shell lines
of the guide run elsewhere: the install in test_wheel.py (the wheel
scripts/wheel builds), the benchmarks in test_examples.py.
"""

import importlib.util
import os
import subprocess
import sys
from pathlib import Path

import pytest

from naosoccer import LocalServer

REPO = Path(__file__).resolve().parents[2]
DOC = REPO / "docs" / "PYTHON.md"


def python_blocks(doc: Path):
    """(first line number, code) of each ```python block, in order."""
    blocks, current, start = [], None, 0
    for number, line in enumerate(doc.read_text().splitlines(), 1):
        if current is None and line.strip() == "```python":
            current, start = [], number + 1
        elif current is not None and line.strip() == "```":
            blocks.append((start, "\n".join(current)))
            current = None
        elif current is not None:
            current.append(line)
    return blocks


BLOCKS = python_blocks(DOC)
#: What a block names when it steps matches in process (the native extension).
IN_PROCESS = ("VectorEnv", "parallel_env(", "naosoccer.env(")


def test_the_guide_has_its_examples():
    assert len(BLOCKS) >= 5, "docs/PYTHON.md lost its examples"
    # The guide starts with what a new user types: install, env, step.
    first = BLOCKS[0][1]
    assert "VectorEnv(" in first and ".step(" in first and len(first.splitlines()) <= 3


@pytest.mark.parametrize("line,code", BLOCKS, ids=[f"PYTHON.md:{n}" for n, _ in BLOCKS])
def test_every_python_snippet_of_python_md_runs(binary, line, code):
    if any(name in code for name in IN_PROCESS) and importlib.util.find_spec("naosoccer._native") is None:
        pytest.skip("the native extension is not built (scripts/wheel --in-place)")
    env = {**os.environ, "PYTHONPATH": str(REPO / "python"), "NAOSOCCER_BIN": binary}
    with LocalServer(binary) as srv:
        env.update(NAOSOCCER_HOST=srv.host, NAOSOCCER_PORT=str(srv.port),
                   BLUE_TOKEN=srv.tokens["blue"], ADMIN_TOKEN=srv.tokens["admin"])
        out = subprocess.run([sys.executable, "-c", code], cwd=REPO, env=env,
                             capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, f"docs/PYTHON.md line {line}:\n{code}\n{out.stderr}"
