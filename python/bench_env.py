#!/usr/bin/env python3
"""Throughput of NaoSoccerParallelEnv in lockstep on loopback.

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


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--binary", help="naosoccer binary (default: $NAOSOCCER_BIN or the repository's target/)")
    ap.add_argument("--minutes", type=float, default=2.0, help="game minutes per match (default 2)")
    ap.add_argument("--matches", type=int, default=2, help="matches through the env (default 2)")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--opponent", default="scripted", choices=("scripted", "idle"))
    args = ap.parse_args()

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
