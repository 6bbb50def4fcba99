"""naosoccer on a Ray cluster: evaluations and leagues whose matches are Ray
tasks, and the PettingZoo env for RLlib (:mod:`naosoccer.ray.rllib`).

Each match is one task that runs ``naosoccer eval --matches 1`` on its node
(:func:`naosoccer.evaluation.play_match`); matches are deterministic by their
seed, so the merged result equals the single-machine ``naosoccer eval``
whatever node played what. Needs the ``ray`` extra (``pip install
'./python[ray]'``); docs/RAY.md in the repository.

Where things come from on a node: this package is shipped to every task
(a Ray ``runtime_env`` ``py_modules`` entry), so the nodes need Ray but not
naosoccer installed. The binary is ``binary=`` if given, else
``$NAOSOCCER_BIN`` as set where the driver runs (passed to the tasks), else
the node's own ``$NAOSOCCER_BIN``, then the repository's ``target/release``
(:func:`naosoccer.find_binary`). Relative paths (team directories, ``--config``,
a relative binary) are taken relative to the driver's working directory when
that directory exists on the node (a shared path, or the same checkout at
the same path), else relative to the task's working directory (a Ray
``runtime_env`` ``working_dir``).
"""

from __future__ import annotations

import json
import os
import time
from typing import Any, Callable, Dict, List, Optional, Sequence

try:
    import ray
except ImportError as e:  # pragma: no cover - depends on the installation
    raise ImportError(
        "naosoccer.ray needs Ray: pip install './python[ray]' (scripts/setup installs it)"
    ) from e

from ..evaluation import EvalSpec, MatchOutcome, eval_document, play_match
from ..league import league_document, pairings
from ..server import BIN_ENV

__all__ = ["connect", "run_eval", "run_eval_outcomes", "run_league", "task_runtime_env"]

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
def _play(spec: EvalSpec, index: int, cwd: str) -> MatchOutcome:
    node = ray.get_runtime_context().get_node_id()
    return play_match(spec, index, cwd=cwd, node=node)


def _play_all(
    specs: Sequence[EvalSpec],
    binary: Optional[str],
    progress: Optional[Callable[[int, int], None]],
) -> List[List[MatchOutcome]]:
    """Every match of every spec as one task each, spread over the nodes."""
    for spec in specs:
        spec.check()
    options: Dict[str, Any] = {"scheduling_strategy": "SPREAD"}
    if binary:
        options["runtime_env"] = {"env_vars": {BIN_ENV: binary}}
    task = _play.options(**options)
    cwd = os.getcwd()
    refs = []
    owner = {}
    for k, spec in enumerate(specs):
        for i in range(spec.matches):
            ref = task.remote(spec, i, cwd)
            refs.append(ref)
            owner[ref] = k
    results: List[List[MatchOutcome]] = [[] for _ in specs]
    pending = list(refs)
    done = 0
    while pending:
        ready, pending = ray.wait(pending, num_returns=1)
        for ref in ready:
            results[owner[ref]].append(ray.get(ref))
            done += 1
        if progress is not None:
            progress(done, len(refs))
    return results


def run_eval(
    spec: EvalSpec,
    *,
    binary: Optional[str] = None,
    progress: Optional[Callable[[int, int], None]] = None,
) -> Dict[str, Any]:
    """Plays ``spec`` on the cluster (:func:`connect` first) and returns what
    ``naosoccer eval --json`` prints for it; ``wall_seconds`` is this run's."""
    doc, _ = run_eval_outcomes(spec, binary=binary, progress=progress)
    return doc


def run_eval_outcomes(
    spec: EvalSpec,
    *,
    binary: Optional[str] = None,
    progress: Optional[Callable[[int, int], None]] = None,
):
    """As :func:`run_eval`, also returning the matches (with their nodes)."""
    start = time.perf_counter()
    [outcomes] = _play_all([spec], binary, progress)
    return eval_document(spec, outcomes, time.perf_counter() - start), sorted(outcomes, key=lambda m: m.index)


def run_league(
    teams: Sequence[str],
    *,
    matches: int,
    seed: int = 0,
    config: Optional[str] = None,
    minutes: Optional[float] = None,
    binary: Optional[str] = None,
    progress: Optional[Callable[[int, int], None]] = None,
) -> Dict[str, Any]:
    """A round robin of ``teams``: every pairing plays ``naosoccer eval
    --matches matches --seed seed --both-sides``; all matches of all
    pairings are tasks at once. Returns :func:`naosoccer.league.league_document`."""
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
    per_pairing = _play_all(specs, binary, progress)
    wall = time.perf_counter() - start
    evals = [eval_document(s, o, wall) for s, o in zip(specs, per_pairing)]
    return league_document(teams, matches, seed, evals, wall)
