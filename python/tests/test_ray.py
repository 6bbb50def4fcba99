"""`python -m naosoccer.ray eval|league` on a real two-node Ray cluster on
this machine (`ray start --head`, a second `ray start --address ...`, one CPU
each, stopped at the end), checked against single-machine `naosoccer eval`.

The nodes are started without naosoccer on their path and without
NAOSOCCER_BIN, from another directory: the package, the binary's path and
the relative team directories reach the tasks the way docs/RAY.md says.
"""

import json
import os
import queue
import re
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import threading
import time

import pytest

ray = pytest.importorskip(
    "ray", reason="Ray is not installed: pip install './python[ray]' (scripts/setup installs it)"
)

from naosoccer.evaluation import EvalSpec, merge_blocks  # noqa: E402
from naosoccer.league import pairings, standings  # noqa: E402

REPO = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
PYTHON_DIR = os.path.join(REPO, "python")
RAY_CLI = os.path.join(os.path.dirname(sys.executable), "ray")
START_TIMEOUT = 180.0


def _free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _quiet_env(**extra):
    """The environment of Ray's processes here: no usage stats, no token
    written into the home directory, no NAOSOCCER_BIN of the test's."""
    env = {k: v for k, v in os.environ.items() if k not in ("NAOSOCCER_BIN", "RAY_ADDRESS", "PYTHONPATH")}
    env.update(RAY_USAGE_STATS_ENABLED="0", RAY_AUTH_MODE="disabled", **extra)
    return env


class _Node:
    """A `ray start --block` process in its own process group: stopping the
    group stops the node's raylet, workers and agents with it."""

    def __init__(self, args, temp_dir, ready):
        self.proc = subprocess.Popen(
            [RAY_CLI, "start", "--block", "--num-cpus=1", "--disable-usage-stats",
             "--dashboard-agent-listen-port=0", "--metrics-export-port=0", *args],
            cwd=temp_dir, env=_quiet_env(), stdin=subprocess.DEVNULL,
            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, start_new_session=True,
        )
        self.log = []
        lines = queue.Queue()
        threading.Thread(target=self._pump, args=(lines,), daemon=True).start()
        deadline = time.monotonic() + START_TIMEOUT
        self.match = None
        while self.match is None:
            try:
                line = lines.get(timeout=max(0.0, deadline - time.monotonic()))
            except queue.Empty:
                line = None
            if line is None:
                self.stop()
                pytest.fail("ray start did not come up:\n" + "".join(self.log[-40:]))
            self.match = ready(line)

    def _pump(self, lines):
        for line in self.proc.stdout:
            self.log.append(line)
            lines.put(line)
        lines.put(None)

    def stop(self):
        pgid = self.proc.pid
        for sig, wait in ((signal.SIGTERM, 5.0), (signal.SIGKILL, 15.0)):
            try:
                os.killpg(pgid, sig)
            except ProcessLookupError:
                return
            deadline = time.monotonic() + wait
            while time.monotonic() < deadline and _group_alive(pgid):
                time.sleep(0.1)
            if not _group_alive(pgid):
                break
        try:
            self.proc.wait(timeout=5)
        except subprocess.TimeoutExpired:
            pass


def _group_alive(pgid):
    for pid in os.listdir("/proc"):
        if pid.isdigit():
            try:
                with open(f"/proc/{pid}/stat") as f:
                    fields = f.read().rsplit(")", 1)[1].split()
            except OSError:
                continue
            # fields[0] is the state, fields[2] the process group.
            if int(fields[2]) == pgid and fields[0] != "Z":
                return True
    return False


@pytest.fixture(scope="module")
def cluster():
    temp_dir = tempfile.mkdtemp(prefix="nsray-")
    nodes = []
    try:
        head = _Node(
            ["--head", "--port=0", f"--temp-dir={temp_dir}", "--include-dashboard=false",
             "--dashboard-port=0", f"--ray-client-server-port={_free_port()}"],
            temp_dir,
            lambda line: re.search(r"ray start --address='([^']+)'", line),
        )
        nodes.append(head)
        address = head.match.group(1)
        nodes.append(_Node([f"--address={address}"], temp_dir, lambda line: "Ray runtime started" in line or None))
        yield address
    finally:
        # The worker node first: stopped after the head, it waits for it.
        for node in reversed(nodes):
            node.stop()
        shutil.rmtree(temp_dir, ignore_errors=True)


def run_cli(address, binary, *args, timeout=600):
    env = _quiet_env(RAY_ADDRESS=address, NAOSOCCER_BIN=binary, PYTHONPATH=PYTHON_DIR)
    out = subprocess.run(
        [sys.executable, "-m", "naosoccer.ray", *args],
        cwd=REPO, env=env, capture_output=True, text=True, timeout=timeout,
    )
    assert out.returncode == 0, out.stderr[-4000:]
    return out.stdout


def binary_eval_text(binary, *args):
    out = subprocess.run([binary, "eval", *args, "--json"], cwd=REPO, capture_output=True, text=True, timeout=600)
    assert out.returncode == 0, out.stderr
    return out.stdout


def binary_eval(binary, *args):
    return json.loads(binary_eval_text(binary, *args))


def without_wall(doc):
    return {k: v for k, v in doc.items() if k != "wall_seconds"}


def test_eval_on_two_nodes_gives_the_binarys_scores(cluster, binary):
    args = ["--blue", "scripted", "--red", "random", "--matches", "16", "--seed", "29", "--minutes", "2"]
    text = run_cli(cluster, binary, "eval", *args, "--json", "--block", "3")
    got = json.loads(text)
    want_text = binary_eval_text(binary, *args)
    want = json.loads(want_text)
    assert len(got["scores"]) == 16
    assert got["scores"] == want["scores"]
    # Everything else too, to the last bit, and printed the same way.
    assert without_wall(got) == without_wall(want)
    wall = re.compile(r'"wall_seconds":[^,}]+')
    assert wall.sub("", text) == wall.sub("", want_text)


def test_matches_spread_over_both_nodes(cluster, binary):
    from naosoccer.ray import connect, default_block_for, run_eval_blocks

    connect(cluster, binary=binary, log_to_driver=False)
    try:
        alive = [n for n in ray.nodes() if n["Alive"]]
        assert len(alive) == 2
        # Two CPUs: blocks of 2, about two a CPU.
        assert default_block_for(6) == 2
        spec = EvalSpec("scripted", "idle", matches=6, seed=3, both_sides=True, minutes=0.2)
        # Six one-match blocks, dealt to the two nodes in turn (Ray's SPREAD
        # alone once put all six on one node).
        played = run_eval_blocks(spec, block=1)
        assert [(b.first, b.matches) for b in played] == [(i, 1) for i in range(6)]
        assert {b.node for b in played} == {n["NodeID"] for n in alive}
        doc = json.loads(merge_blocks(played, binary=binary))
        want = binary_eval(binary, "--blue", "scripted", "--red", "idle", "--matches", "6", "--seed", "3",
                           "--both-sides", "--minutes", "0.2")
        assert without_wall(doc) == without_wall(want)
    finally:
        ray.shutdown()


def test_blocks_are_dealt_to_nodes_by_their_cpus():
    from naosoccer.ray import node_turns

    def node(name, cpus, alive=True):
        return {"NodeID": name, "Alive": alive, "Resources": {"CPU": float(cpus), "memory": 1e9}}

    assert node_turns([]) == []
    assert node_turns([node("b", 1), node("a", 1)]) == ["a", "b"]
    # Three CPUs against one: three turns in four; a dead node and a node
    # without CPUs get none.
    nodes = [node("c", 1), node("a", 3), node("d", 4, alive=False), node("e", 0)]
    assert node_turns(nodes) == ["a", "c", "a", "a"]
    assert node_turns([node("x", 0)]) == []


def test_league_of_four_matches_single_machine_evals(cluster, binary, tmp_path):
    teams = ["scripted", "random", "idle", "ppo:assets/policies/ppo-team-seed1"]
    common = ["--matches", "2", "--seed", "5", "--minutes", "1"]
    out_dir = tmp_path / "league"
    md = run_cli(cluster, binary, "league", *teams, *common, "--out", str(out_dir))
    doc = json.loads((out_dir / "league.json").read_text())
    assert (out_dir / "league.md").read_text() == md
    assert doc["teams"] == teams and doc["matches_per_pairing"] == 2 and doc["both_sides"] is True

    # Every pairing is `naosoccer eval --both-sides` of the same arguments.
    evals = []
    for (i, j), got in zip(pairings(len(teams)), doc["pairings"]):
        want = binary_eval(binary, "--blue", teams[i], "--red", teams[j], *common, "--both-sides")
        assert without_wall(got) == without_wall(want), (teams[i], teams[j])
        evals.append(want)
    assert len(evals) == 6
    table = standings(teams, evals)
    assert doc["standings"] == table
    assert sum(r["matches"] for r in table) == 6 * 2 * 2
    assert sum(r["wins"] for r in table) == sum(r["losses"] for r in table)
    for r in table:
        assert f"`{r['team']}`" in md
        assert r["rating_low"] < r["rating"] < r["rating_high"]
    ranks = {r["team"]: r["rank"] for r in table}
    assert ranks["scripted"] < ranks["idle"]
