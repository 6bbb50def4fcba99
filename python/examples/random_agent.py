#!/usr/bin/env python3
"""Plays one match with uniformly random actions for the four blue robots and
prints the final score and statistics.

By default a private server is started (the repository's target/ build, or
$NAOSOCCER_BIN); --host/--port/--token join a running one instead.

    .venv/bin/python python/examples/random_agent.py --minutes 2 --seed 7
"""

import argparse
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))

from naosoccer import NaoSoccerParallelEnv  # noqa: E402


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--minutes", type=float, default=10.0, help="match length in game minutes (default 10)")
    ap.add_argument("--seed", type=int, default=1, help="match seed; also seeds the random actions")
    ap.add_argument("--opponent", default="scripted", choices=("scripted", "idle"))
    ap.add_argument("--host", help="join a running server instead of starting one")
    ap.add_argument("--port", type=int, default=7878)
    ap.add_argument("--token", help="blue token of the running server")
    ap.add_argument("--admin-token", help="admin token of the running server (to create the match)")
    args = ap.parse_args()

    kw = {}
    if args.host:
        kw = dict(host=args.host, port=args.port, token=args.token, admin_token=args.admin_token)
    env = NaoSoccerParallelEnv(minutes=args.minutes, opponent=args.opponent, **kw)
    try:
        obs, infos = env.reset(seed=args.seed)
        for agent in env.possible_agents:
            env.action_space(agent).seed(args.seed)
        returns = dict.fromkeys(env.possible_agents, 0.0)
        steps = 0
        while env.agents:
            actions = {a: env.action_space(a).sample() for a in env.agents}
            obs, rewards, terms, truncs, infos = env.step(actions)
            steps += 1
            for a, r in rewards.items():
                returns[a] += r
        final = infos[env.possible_agents[0]]
    finally:
        env.close()

    end = final["match_end"]
    stats = end["stats"]
    print(f"match {final['match_id']}, seed {args.seed}: random (blue) vs {args.opponent} (red), {steps} ticks")
    print(f"final score: blue {end['score']['blue']} - {end['score']['red']} red")
    print()
    print(f"{'':<16}{'blue':>10}{'red':>10}")
    rows = [
        ("goals", lambda t: str(t["goals"])),
        ("ball control", lambda t: f"{100 * t['control_rate']:.1f}%"),
        ("passes", lambda t: str(t["passes"])),
        ("shots", lambda t: str(t["shots"])),
        ("falls", lambda t: str(t["falls"])),
        ("out of bounds", lambda t: str(t["out_of_bounds"])),
    ]
    for name, f in rows:
        print(f"{name:<16}{f(stats['blue']):>10}{f(stats['red']):>10}")
    print()
    print("return per robot (shaped reward): " + ", ".join(f"{a} {r:.1f}" for a, r in returns.items()))
    return 0


if __name__ == "__main__":
    sys.exit(main())
