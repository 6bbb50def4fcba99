"""naosoccer on a Ray cluster: evaluations and leagues whose matches are
played in blocks by Ray tasks, and the PettingZoo env for RLlib
(:mod:`naosoccer.ray.rllib`).

Each task runs ``naosoccer eval --first-match I --matches N --json`` on its
node for one block of matches (:func:`naosoccer.evaluation.play_block`); the
driver merges the blocks with ``naosoccer eval --merge``. Matches are
deterministic by their seed, so the result equals the single-machine
``naosoccer eval`` whatever node played what, and the statistics are the
binary's own. Needs the ``ray`` extra (``pip install './python[ray]'``);
docs/RAY.md in the repository.

Where things come from on a node: this package is shipped to every task
(a Ray ``runtime_env`` ``py_modules`` entry), so the nodes need Ray but not
naosoccer installed. The binary is ``binary=`` if given, else
``$NAOSOCCER_BIN`` as set where the driver runs (passed to the tasks), else
the node's own ``$NAOSOCCER_BIN``, then the repository's ``target/release``
(:func:`naosoccer.find_binary`); the driver finds its own the same way for
the merge. Relative paths (team directories, ``--config``, a relative
binary) are taken relative to the driver's working directory when that
directory exists on the node (a shared path, or the same checkout at the
same path), else relative to the task's working directory (a Ray
``runtime_env`` ``working_dir``).
"""

from __future__ import annotations

import json
import os
import time
from typing import Any, Callable, Dict, List, Optional, Sequence

try:
    import ray
    from ray.util.scheduling_strategies import NodeAffinitySchedulingStrategy
except ImportError as e:  # pragma: no cover - depends on the installation
    raise ImportError(
        "naosoccer.ray needs Ray: pip install './python[ray]' (scripts/setup installs it)"
    ) from e

from ..evaluation import Block, EvalSpec, blocks, default_block, merge_blocks, play_block
from ..league import league_document, pairings
from ..server import BIN_ENV

__all__ = [
    "connect",
    "default_block_for",
    "node_turns",
    "run_eval",
    "run_eval_blocks",
    "run_eval_text",
    "run_league",
    "task_runtime_env",
]

_PACKAGE_DIR = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def connect(
    address: Optional[str] = None,
    num_cpus: Optional[int] = None,
    binary: Optional[str] = None,
    **init_args: Any,
) -> None:
    """Connects to the cluster at ``address`` (default ``$RAY_ADDRESS``), or
    starts a local one (``num_cpus`` worker slots, default all cores) when
    neither is given, with :func:`task_runtime_env` as the job's runtime
    environment (unless ``runtime_env=`` is passed). Does nothing when Ray is
    already initialised: then pass ``runtime_env=task_runtime_env()`` to your
    own ``ray.init``."""
    if ray.is_initialized():
        return
    address = address or os.environ.get("RAY_ADDRESS") or None
    init_args.setdefault("runtime_env", task_runtime_env(binary))
    if address is None:
        ray.init(address="local", num_cpus=num_cpus, include_dashboard=False, **init_args)
    else:
        ray.init(address=address, **init_args)


def task_runtime_env(binary: Optional[str] = None) -> Dict[str, Any]:
    """The runtime environment the tasks need: this package as a
    ``py_modules`` entry (uploaded to the nodes), and ``NAOSOCCER_BIN`` when
    the driver names a binary (``binary`` or its own ``$NAOSOCCER_BIN``).

    Inside a Ray job (``ray job submit``) Ray merges this with the job's own
    runtime environment and refuses fields or variables set in both, so what
    the job already sets is left out: the job's ``NAOSOCCER_BIN`` is the one
    the driver sees anyway."""
    env: Dict[str, Any] = {"py_modules": [_PACKAGE_DIR]}
    binary = binary or os.environ.get(BIN_ENV)
    if binary:
        env["env_vars"] = {BIN_ENV: binary}
    job = _job_runtime_env()
    for key in list(env):
        if key == "env_vars":
            env[key] = {k: v for k, v in env[key].items() if k not in (job.get("env_vars") or {})}
            if not env[key]:
                del env[key]
        elif key in job:
            del env[key]
    return env


def _job_runtime_env() -> Dict[str, Any]:
    """The runtime environment of the Ray job this driver runs in (set by
    Ray's job manager in the driver's environment), or {}."""
    text = os.environ.get("RAY_JOB_CONFIG_JSON_ENV_VAR")
    if not text:
        return {}
    try:
        return dict(json.loads(text).get("runtime_env") or {})
    except (ValueError, AttributeError):
        return {}


@ray.remote(num_cpus=1)
def _play(spec: EvalSpec, first: int, matches: int, cwd: str) -> Block:
    node = ray.get_runtime_context().get_node_id()
    return play_block(spec, first, matches, cwd=cwd, node=node)


def default_block_for(matches: int) -> int:
    """The default block size on the connected cluster: about two blocks a
    CPU, at most :data:`naosoccer.evaluation.MAX_BLOCK` matches."""
    return default_block(matches, ray.cluster_resources().get("CPU", 1))


def node_turns(nodes: Sequence[Dict[str, Any]]) -> List[str]:
    """The order in which blocks are dealt to the nodes: of the alive nodes
    with CPUs (as ``ray.nodes()`` lists them), sorted by node id, every node
    once a round while it has CPUs left in that round, so a node gets blocks
    in proportion to its CPUs. Block ``k`` goes to turn ``k`` modulo the
    length. Empty when no node has a CPU."""
    cpus = {}
    for n in nodes:
        count = int((n.get("Resources") or {}).get("CPU", 0))
        if n.get("Alive") and count > 0:
            cpus[n["NodeID"]] = count
    order = sorted(cpus)
    turns: List[str] = []
    for r in range(max(cpus.values(), default=0)):
        turns.extend(node for node in order if cpus[node] > r)
    return turns


def _play_all(
    specs: Sequence[EvalSpec],
    block: Optional[int],
    binary: Optional[str],
    progress: Optional[Callable[[int, int], None]],
) -> List[List[Block]]:
    """Every spec's matches in blocks of ``block`` (default:
    :func:`default_block_for` all their matches), one task a block, dealt
    to the nodes in turn (:func:`node_turns`). A task waits for its node
    when the node is busy and goes elsewhere only when its node is gone
    (Ray's soft node affinity), so every node plays its share even when
    Ray's own placement would have packed the tasks on one node."""
    for spec in specs:
        spec.check()
    if block is None:
        block = default_block_for(sum(s.matches for s in specs))
    options: Dict[str, Any] = {}
    if binary:
        options["runtime_env"] = {"env_vars": {BIN_ENV: binary}}
    turns = node_turns(ray.nodes())
    cwd = os.getcwd()
    owner = {}
    total = 0
    dealt = 0
    for k, spec in enumerate(specs):
        for first, n in blocks(spec.matches, block):
            if turns:
                node = turns[dealt % len(turns)]
                strategy: Any = NodeAffinitySchedulingStrategy(node_id=node, soft=True)
            else:
                strategy = "SPREAD"
            task = _play.options(scheduling_strategy=strategy, **options)
            owner[task.remote(spec, first, n, cwd)] = (k, n)
            total += n
            dealt += 1
    results: List[List[Block]] = [[] for _ in specs]
    pending = list(owner)
    done = 0
    while pending:
        ready, pending = ray.wait(pending, num_returns=1)
        for ref in ready:
            k, n = owner[ref]
            results[k].append(ray.get(ref))
            done += n
        if progress is not None:
            progress(done, total)
    return results


def run_eval_blocks(
    spec: EvalSpec,
    *,
    block: Optional[int] = None,
    binary: Optional[str] = None,
    progress: Optional[Callable[[int, int], None]] = None,
) -> List[Block]:
    """Plays ``spec`` on the cluster (:func:`connect` first) in blocks of
    ``block`` matches, one task each; the blocks in order of their first
    match, each with the node that played it. ``progress(done, total)``
    counts matches."""
    [played] = _play_all([spec], block, binary, progress)
    return sorted(played, key=lambda b: b.first)


def run_eval_text(
    spec: EvalSpec,
    *,
    json_out: bool = True,
    block: Optional[int] = None,
    binary: Optional[str] = None,
    progress: Optional[Callable[[int, int], None]] = None,
) -> str:
    """What ``naosoccer eval`` prints for ``spec`` (the JSON line, or the
    table), played on the cluster and merged by the binary here. Its
    ``wall_seconds`` is the sum of the blocks' times."""
    played = run_eval_blocks(spec, block=block, binary=binary, progress=progress)
    return merge_blocks(played, binary=binary, json_out=json_out)


def run_eval(
    spec: EvalSpec,
    *,
    block: Optional[int] = None,
    binary: Optional[str] = None,
    progress: Optional[Callable[[int, int], None]] = None,
) -> Dict[str, Any]:
    """The object ``naosoccer eval --json`` prints for ``spec``, played on
    the cluster (:func:`run_eval_text`)."""
    return json.loads(run_eval_text(spec, block=block, binary=binary, progress=progress))


def run_league(
    teams: Sequence[str],
    *,
    matches: int,
    seed: int = 0,
    config: Optional[str] = None,
    minutes: Optional[float] = None,
    block: Optional[int] = None,
    binary: Optional[str] = None,
    progress: Optional[Callable[[int, int], None]] = None,
) -> Dict[str, Any]:
    """A round robin of ``teams``: every pairing plays ``naosoccer eval
    --matches matches --seed seed --both-sides``; the blocks of all
    pairings are tasks at once, and each pairing is merged by the binary.
    Returns :func:`naosoccer.league.league_document`."""
    if len(teams) < 2:
        raise ValueError("a league needs at least two teams")
    if len(set(teams)) != len(teams):
        raise ValueError("a team appears twice in the league")
    specs = [
        EvalSpec(
            blue=teams[i], red=teams[j], matches=matches, seed=seed,
            both_sides=True, config=config, minutes=minutes,
        )
        for i, j in pairings(len(teams))
    ]
    start = time.perf_counter()
    per_pairing = _play_all(specs, block, binary, progress)
    evals = [json.loads(merge_blocks(played, binary=binary)) for played in per_pairing]
    wall = time.perf_counter() - start
    return league_document(teams, matches, seed, evals, wall)
