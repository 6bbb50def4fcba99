"""Evaluations played in blocks of matches and merged again by the binary.

``naosoccer eval --first-match I --matches N --json`` plays matches ``I`` to
``I + N - 1`` of an evaluation, with the seeds and sides they have in one run
of all its matches, and lists every match in its ``results``. ``naosoccer
eval --merge FILE.json ...`` merges such outputs into exactly what one run
over all their matches prints (the table, or with ``--json`` the object);
its ``wall_seconds`` is the sum of the blocks'. The binary owns the seeds and
the statistics: this module only builds the command lines, runs them and
hands their outputs to the merge.

Nothing here needs Ray: :mod:`naosoccer.ray` sends :func:`play_block` to the
nodes of a cluster and merges on the driver with :func:`merge_blocks`.
"""

from __future__ import annotations

import json
import os
import subprocess
import tempfile
from dataclasses import dataclass
from typing import Any, Dict, List, Optional, Sequence, Tuple

from .server import BIN_ENV, find_binary

MASK64 = (1 << 64) - 1
#: The most matches one block plays by default: a block's matches run side
#: by side in one process, so its memory grows with them.
MAX_BLOCK = 32


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

    def check(self) -> None:
        if self.matches < 1:
            raise ValueError("--matches must be at least 1")
        if not 0 <= self.seed <= MASK64:
            raise ValueError(f"--seed must be in 0..2^64-1, got {self.seed}")
        if self.minutes is not None and not self.minutes > 0:
            raise ValueError(f"--minutes must be positive, got {self.minutes}")


@dataclass(frozen=True)
class Block:
    """Matches ``first .. first + matches - 1`` of an evaluation, played:
    ``text`` is the ``naosoccer eval --json`` output, ``node`` where it was
    played (a Ray node id, or "" when played locally)."""

    first: int
    matches: int
    text: str
    node: str = ""


def default_block(matches: int, cpus: float) -> int:
    """Matches a block: about two blocks per CPU, at most :data:`MAX_BLOCK`."""
    slots = max(1, int(cpus)) * 2
    return max(1, min(MAX_BLOCK, -(-matches // slots)))


def blocks(matches: int, block: int) -> List[Tuple[int, int]]:
    """``matches`` cut into consecutive blocks of ``block`` (the last may be
    shorter), as (first match, matches)."""
    if block < 1:
        raise ValueError(f"a block has at least 1 match, got {block}")
    return [(first, min(block, matches - first)) for first in range(0, matches, block)]


def block_command(binary: str, spec: EvalSpec, first: int, matches: int) -> List[str]:
    """The ``naosoccer eval`` command line that plays matches ``first ..
    first + matches - 1`` of ``spec`` on one thread and prints ``--json``."""
    cmd = [
        binary, "eval", "--blue", spec.blue, "--red", spec.red,
        "--matches", str(matches), "--first-match", str(first),
        "--seed", str(spec.seed), "--threads", "1", "--json",
    ]
    if spec.both_sides:
        cmd.append("--both-sides")
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


def _run(cmd: List[str], cwd: str) -> str:
    out = subprocess.run(cmd, cwd=cwd, stdin=subprocess.DEVNULL, capture_output=True, text=True)
    if out.returncode != 0:
        raise RuntimeError(f"{' '.join(cmd)} failed (exit {out.returncode}): {out.stderr.strip()[-2000:]}")
    return out.stdout


def play_block(
    spec: EvalSpec,
    first: int,
    matches: int,
    *,
    binary: Optional[str] = None,
    cwd: Optional[str] = None,
    node: str = "",
) -> Block:
    """Plays matches ``first .. first + matches - 1`` of ``spec`` in a
    ``naosoccer eval`` child process. Relative team directories,
    ``--config`` and ``binary`` are taken relative to ``cwd`` when that
    directory exists here, else to the current directory."""
    base = cwd if cwd and os.path.isdir(cwd) else os.getcwd()
    exe = resolve_binary(base, binary)
    text = _run(block_command(exe, spec, first, matches), base)
    return Block(first=first, matches=matches, text=text, node=node)


def merge_blocks(
    played: Sequence[Block],
    *,
    binary: Optional[str] = None,
    json_out: bool = True,
) -> str:
    """What ``naosoccer eval --merge`` prints for the blocks (in any order):
    with ``json_out`` the JSON line, else the table. The binary refuses
    blocks of different evaluations, overlaps and gaps."""
    if not played:
        raise ValueError("no blocks to merge")
    exe = resolve_binary(os.getcwd(), binary)
    with tempfile.TemporaryDirectory(prefix="naosoccer-merge-") as tmp:
        files = []
        for b in sorted(played, key=lambda b: b.first):
            # Named by their matches, which is what the merge's errors cite.
            path = os.path.join(tmp, f"matches-{b.first}-{b.first + b.matches - 1}.json")
            with open(path, "w", encoding="utf-8") as f:
                f.write(b.text)
            files.append(path)
        cmd = [exe, "eval", "--merge", *files] + (["--json"] if json_out else [])
        return _run(cmd, tmp)


def evaluate(
    spec: EvalSpec,
    *,
    block: int = MAX_BLOCK,
    binary: Optional[str] = None,
    cwd: Optional[str] = None,
) -> Dict[str, Any]:
    """``spec`` played here, block after block, and merged: the object
    ``naosoccer eval --json`` prints for it (``wall_seconds`` the sum of the
    blocks')."""
    spec.check()
    played = [play_block(spec, f, n, binary=binary, cwd=cwd) for f, n in blocks(spec.matches, block)]
    return json.loads(merge_blocks(played, binary=binary))
