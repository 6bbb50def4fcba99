#!/usr/bin/env python3
"""Throughput of the Python envs.

With ``--vector``: ``naosoccer.VectorEnv``, matches stepped in this process
by the native extension, one team's four robots driven from Python with
uniformly random actions against the opponent, every match auto-resetting;
it prints match ticks per second (one tick of one match; a ``step`` is one
tick of every match), per second of CPU time, and how a step's time splits
between the native call and the Python around it.

    .venv/bin/python python/bench_env.py --vector [--num-matches 8] [--seconds 20]

Without it: NaoSoccerParallelEnv in lockstep on loopback.

Starts a private server (or uses --binary / $NAOSOCCER_BIN), plays whole
matches through the env with a cheap fixed action pattern and prints team
steps per second (one step = one control tick with all four robots' actions
sent and the next four observations decoded and encoded as vectors). For
comparison it also times the low-level client alone (no numpy encoding) and
the same match played in process by ``naosoccer match`` (no sockets).

    .venv/bin/python python/bench_env.py [--minutes 2] [--matches 2]
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from naosoccer import Client, LocalServer, NaoSoccerParallelEnv  # noqa: E402


def bench_env(env: NaoSoccerParallelEnv, seed: int, matches: int) -> tuple:
    steps = 0
    start = time.perf_counter()
    for m in range(matches):
        env.reset(seed=seed + m)
        t = 0
        while env.agents:
            env.step({a: (t // 10 + p) % 5 for p, a in enumerate(env.agents)})
            t += 1
        steps += t
    return steps, time.perf_counter() - start


def bench_client(server: LocalServer, seed: int, minutes: float) -> tuple:
    with Client(server.host, server.port) as c:
        info = c.create_match(server.tokens["admin"], seed=seed, minutes=minutes, fill="scripted", start_players=4)
        c.join("blue", server.tokens["blue"], range(4), info["match_id"])
        steps = 0
        start = time.perf_counter()
        while True:
            msg = c.recv()
            if msg["type"] == "match_end":
                break
            c.send_actions(msg["tick"], [(p, (msg["tick"] // 10 + p) % 5) for p in range(4)])
            steps += 1
        return steps, time.perf_counter() - start


class _TimedNative:
    """The env's native object with its ``step`` timed: what the Rust side
    (the matches stepped, the arrays built) costs, apart from the Python of
    ``VectorEnv.step`` around it."""

    def __init__(self, native) -> None:
        self.native = native
        self.seconds = 0.0

    def step(self, actions):
        start = time.perf_counter()
        out = self.native.step(actions)
        self.seconds += time.perf_counter() - start
        return out

    def __getattr__(self, name):
        return getattr(self.native, name)


def bench_vector(args: argparse.Namespace) -> int:
    from naosoccer import VectorEnv

    env = VectorEnv(args.num_matches, opponent=args.opponent, minutes=args.minutes, seed=args.seed,
                    threads=args.threads)
    env.reset()
    rng = np.random.default_rng(args.seed)
    # Warm-up: the first ticks pay for page faults.
    for _ in range(20):
        env.step(rng.integers(0, env.num_actions, size=(env.num_envs, env.robots)))
    native = env._native = _TimedNative(env._native)
    steps = 0
    ended = 0
    acting = 0.0
    stepping = 0.0
    clock = time.perf_counter
    start = clock()
    cpu_start = time.process_time()
    while clock() - start < args.seconds:
        t0 = clock()
        actions = rng.integers(0, env.num_actions, size=(env.num_envs, env.robots))
        t1 = clock()
        _, _, term, _, _ = env.step(actions)
        stepping += clock() - t1
        acting += t1 - t0
        ended += int(term.sum())
        steps += 1
    secs = clock() - start
    cpu = time.process_time() - cpu_start
    ticks = steps * env.num_envs
    print(f"VectorEnv: {env.num_envs} matches, {env.robots} robots from Python (random actions) "
          f"vs {args.opponent}, {env.threads} threads, {os.cpu_count()} CPUs")
    print(f"{steps} steps, {ticks} match ticks in {secs:.2f} s = {ticks / secs:,.0f} match ticks/s "
          f"({steps / secs:,.0f} steps/s; {ended} matches ended)")
    # On a machine other work shares, wall-clock speed says more about the
    # other work than about the env: CPU time says what each tick costs, and
    # the load average how shared the machine was.
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    print(f"{cpu:.2f} s of CPU = {ticks / cpu:,.0f} match ticks per CPU-second; "
          f"load average {load:.1f} on {os.cpu_count()} CPUs")
    # Where a step's wall time goes: the random actions (numpy), the Python
    # of VectorEnv.step, and its native call (the matches stepped on the
    # env's threads, the output arrays built; with threads, waiting for the
    # last match too); what is left is this loop.
    per = 1e6 / steps
    wrapper = stepping - native.seconds
    rest = secs - acting - stepping
    print(f"per step (us): native step {native.seconds * per:.1f}, VectorEnv.step's Python {wrapper * per:.1f}, "
          f"random actions {acting * per:.1f}, loop {rest * per:.1f}; "
          f"native {100 * native.seconds / secs:.1f}% of the time")
    target = 10_000
    print(f"target >= {target:,} match ticks/s: {'met' if ticks / secs >= target else 'NOT met'}")
    return 0


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--binary", help="naosoccer binary (default: $NAOSOCCER_BIN or the repository's target/)")
    ap.add_argument("--minutes", type=float, default=2.0, help="game minutes per match (default 2)")
    ap.add_argument("--matches", type=int, default=2, help="matches through the env (default 2)")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--opponent", default="scripted",
                    help="scripted | idle (socket env); with --vector any policy spec `naosoccer eval` accepts")
    ap.add_argument("--vector", action="store_true", help="benchmark the in-process VectorEnv instead")
    ap.add_argument("--num-matches", type=int, default=8, help="with --vector: matches stepped together (default 8)")
    ap.add_argument("--threads", type=int, default=None, help="with --vector: stepping threads (default: CPUs)")
    ap.add_argument("--seconds", type=float, default=20.0, help="with --vector: how long to measure (default 20)")
    args = ap.parse_args()
    if args.vector:
        return bench_vector(args)
    if args.opponent not in ("scripted", "idle"):
        ap.error("the socket env's opponent is scripted or idle")

    env = NaoSoccerParallelEnv(binary=args.binary, minutes=args.minutes, opponent=args.opponent)
    assert env.server is not None
    binary = env.server.binary
    print(f"binary: {binary}")
    try:
        steps, secs = bench_env(env, args.seed, args.matches)
        env_rate = steps / secs
        raw_steps, raw_secs = bench_client(env.server, args.seed, args.minutes)
    finally:
        env.close()
    cli = json.loads(
        subprocess.run(
            [binary, "match", "--seed", str(args.seed), "--minutes", str(args.minutes),
             "--blue", "random", "--red", args.opponent, "--json"],
            check=True, capture_output=True, text=True,
        ).stdout
    )
    in_process = cli["ticks"] / max(cli["wall_seconds"], 1e-9)
    print(f"env (PettingZoo, 4 agents, {args.opponent} opponent): {steps} team steps in {secs:.2f} s = {env_rate:,.0f} team steps/s")
    print(f"low-level client only:                  {raw_steps} team steps in {raw_secs:.2f} s = {raw_steps / raw_secs:,.0f} team steps/s")
    print(f"in-process match (no sockets):          {cli['ticks']} ticks in {cli['wall_seconds']:.2f} s = {in_process:,.0f} ticks/s")
    target = 1000
    print(f"target >= {target} team steps/s: {'met' if env_rate >= target else 'NOT met'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
