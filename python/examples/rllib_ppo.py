#!/usr/bin/env python3
"""Multi-agent PPO with RLlib (new API stack) over the in-process PettingZoo
env: one policy shared by the four blue robots against the built-in scripted
team.

Each env runner is a Ray actor stepping its own match in process
(``naosoccer.parallel_env``, no server); learning runs in this process.
Connects to the Ray cluster in ``$RAY_ADDRESS``, or starts a local one.
Prints, per iteration, the env steps (control ticks of a match; each is four
robot steps) sampled so far, the mean team return of the finished matches,
and env steps per second of wall-clock time (sampling and learning
together). Needs the ``rllib`` extra (``pip install './python[rllib]'``:
Ray with RLlib, and torch).

The defaults show the plumbing in a few minutes on two cores rather than a
strong team; raise --iterations for more.

    .venv/bin/python python/examples/rllib_ppo.py [--env-runners 2] [--iterations 5]
"""

from __future__ import annotations

import argparse
import os
import sys
import time

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))

try:
    import ray
except ImportError as e:  # pragma: no cover - reported to the user
    sys.exit(f"this example needs Ray with RLlib and torch: pip install './python[rllib]' ({e})")

from naosoccer.ray import task_runtime_env  # noqa: E402
from naosoccer.ray.rllib import ppo_config  # noqa: E402


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--env-runners", type=int, default=2, help="env runner actors, each stepping its own match [default: 2]")
    p.add_argument("--iterations", type=int, default=5, help="training iterations [default: 5]")
    p.add_argument("--minutes", type=float, default=1.0, help="match length in minutes [default: 1]")
    p.add_argument("--train-batch", type=int, default=4000, help="env steps a training batch [default: 4000]")
    p.add_argument("--minibatch", type=int, default=500, help="minibatch size [default: 500]")
    p.add_argument("--epochs", type=int, default=4, help="passes over a batch [default: 4]")
    p.add_argument("--seed", type=int, default=0, help="first match seed and RLlib's seed [default: 0]")
    args = p.parse_args()

    # The env runners import naosoccer: ship this tree's package with the job.
    address = os.environ.get("RAY_ADDRESS") or "local"
    ray.init(address=address, runtime_env=task_runtime_env(), include_dashboard=False, log_to_driver=False)
    config = ppo_config(
        env_runners=args.env_runners,
        minutes=args.minutes,
        seed=args.seed,
        train_batch=args.train_batch,
        minibatch=args.minibatch,
        epochs=args.epochs,
    )
    algo = config.build_algo()
    steps_before = 0
    total_time = 0.0
    try:
        for it in range(1, args.iterations + 1):
            start = time.perf_counter()
            result = algo.train()
            elapsed = time.perf_counter() - start
            runners = result.get("env_runners", {})
            steps = int(runners.get("num_env_steps_sampled_lifetime", 0))
            ret = runners.get("episode_return_mean")
            rate = (steps - steps_before) / elapsed if elapsed > 0 else float("nan")
            # The first iteration also starts the servers and warms up.
            if it > 1:
                total_time += elapsed
            ret_text = f"{ret:.2f}" if isinstance(ret, (int, float)) else "n/a (no match finished yet)"
            print(f"iteration {it}: {steps} env steps, mean team return {ret_text}, {rate:.0f} env steps/s", flush=True)
            if it == 1:
                first_steps = steps
            steps_before = steps
        if args.iterations > 1 and total_time > 0:
            print(
                f"{args.env_runners} env runner(s): {(steps_before - first_steps) / total_time:.0f} env steps/s "
                f"({4 * (steps_before - first_steps) / total_time:.0f} robot steps/s) over iterations 2..{args.iterations}"
            )
        print(f"trained {steps_before} env steps with RLlib PPO, one policy shared by the team's four robots")
    finally:
        algo.stop()
        ray.shutdown()
    return 0


if __name__ == "__main__":
    sys.exit(main())
