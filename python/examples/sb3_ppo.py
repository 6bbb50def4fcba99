#!/usr/bin/env python3
"""Trains one Stable-Baselines3 PPO policy shared by the four blue robots
against the built-in scripted team, then reports its score against that team.

The match is the in-process PettingZoo env (``naosoccer.parallel_env``: no
server), turned into an SB3 ``VecEnv`` of four sub-environments, one per
robot (``TeamVecEnv`` below): SB3 sees four parallel environments that
advance together, so one network learns from all four robots' steps
(parameter sharing; the observation's one-hot ``me*`` entries tell the robots
apart). The robots see the shipped teams' observation layout and choose among
the paper's five actions (SB3's PPO has no action masks). Needs the ``sb3``
extra (``pip install './python[sb3]'``: stable-baselines3 and torch).

The default budget is small (well under a minute of training on two cores)
and shows the plumbing rather than a strong team; raise --timesteps for more.

    python python/examples/sb3_ppo.py [--timesteps 20000] [--eval-matches 2]
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from typing import Any, List, Optional, Sequence

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))

import naosoccer  # noqa: E402
from naosoccer import ParallelMatchEnv  # noqa: E402

try:
    import torch
    from stable_baselines3 import PPO
    from stable_baselines3.common.vec_env import VecEnv
except ImportError as e:  # pragma: no cover - reported to the user
    sys.exit(f"this example needs the sb3 extra (pip install './python[sb3]'): {e}")


class TeamVecEnv(VecEnv):
    """The team's robots as the sub-environments of one SB3 VecEnv.

    One ``step_wait`` is one control tick of the match. When the match ends
    every sub-environment is done at once; SB3's convention is then followed:
    the final observation goes into ``infos[i]["terminal_observation"]`` and
    the returned observation is the first of a fresh match (the next seed).
    """

    def __init__(self, env: ParallelMatchEnv, seed: int = 0) -> None:
        self.env = env
        self.agents = list(env.possible_agents)
        self._seed = seed
        self._actions: Optional[np.ndarray] = None
        super().__init__(len(self.agents), env.observation_space(self.agents[0]), env.action_space(self.agents[0]))

    def _stack(self, obs: dict) -> np.ndarray:
        return np.stack([obs[a] for a in self.agents])

    def reset(self) -> np.ndarray:
        obs, _ = self.env.reset(seed=self._seed)
        self._seed += 1
        return self._stack(obs)

    def step_async(self, actions: np.ndarray) -> None:
        self._actions = actions

    def step_wait(self):
        assert self._actions is not None
        acts = {a: int(self._actions[i]) for i, a in enumerate(self.agents)}
        obs, rew, term, trunc, infos = self.env.step(acts)
        rewards = np.array([rew[a] for a in self.agents], dtype=np.float32)
        done = all(term[a] or trunc[a] for a in self.agents)
        out_infos: List[dict] = []
        for a in self.agents:
            info = {}
            if done:
                info["terminal_observation"] = obs[a]
                info["TimeLimit.truncated"] = bool(trunc[a])
                info["score"] = infos[a]["score"]
                info["stats"] = infos[a]["stats"]
            out_infos.append(info)
        stacked = self.reset() if done else self._stack(obs)
        return stacked, rewards, np.full(self.num_envs, done), out_infos

    def close(self) -> None:
        self.env.close()

    def get_attr(self, attr_name: str, indices: Any = None) -> List[Any]:
        value = None if attr_name == "render_mode" else getattr(self.env, attr_name)
        return [value] * len(self._indices(indices))

    def set_attr(self, attr_name: str, value: Any, indices: Any = None) -> None:
        setattr(self.env, attr_name, value)

    def env_method(self, method_name: str, *args: Any, indices: Any = None, **kwargs: Any) -> List[Any]:
        result = getattr(self.env, method_name)(*args, **kwargs)
        return [result] * len(self._indices(indices))

    def env_is_wrapped(self, wrapper_class: type, indices: Any = None) -> List[bool]:
        return [False] * len(self._indices(indices))

    def _indices(self, indices: Any) -> Sequence[int]:
        if indices is None:
            return range(self.num_envs)
        if isinstance(indices, int):
            return [indices]
        return list(indices)


def evaluate(model: Optional[PPO], env: ParallelMatchEnv, matches: int, seed: int) -> List[dict]:
    """Plays ``matches`` whole matches; ``model=None`` plays uniformly random
    actions. Returns each match's final infos (score and statistics)."""
    rng = np.random.default_rng(seed)
    ends = []
    for m in range(matches):
        obs, _ = env.reset(seed=seed + m)
        while env.agents:
            batch = np.stack([obs[a] for a in env.agents])
            if model is None:
                acts = rng.integers(0, env.num_actions, size=len(env.agents))
            else:
                acts, _ = model.predict(batch, deterministic=True)
            obs, _, _, _, infos = env.step({a: int(acts[i]) for i, a in enumerate(env.agents)})
        ends.append(infos[env.possible_agents[0]])
    return ends


def summarise(name: str, ends: List[dict]) -> None:
    gf = [e["score"]["blue"] for e in ends]
    ga = [e["score"]["red"] for e in ends]
    ctl = [e["stats"]["blue"]["control_rate"] for e in ends]
    passes = [e["stats"]["blue"]["passes"] for e in ends]
    print(
        f"{name:<10} vs scripted over {len(ends)} match(es): goals for {np.mean(gf):.2f}, "
        f"against {np.mean(ga):.2f}, ball control {100 * np.mean(ctl):.1f}%, passes {np.mean(passes):.1f}  "
        f"(scores: {', '.join(f'{a}-{b}' for a, b in zip(gf, ga))})"
    )


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--timesteps", type=int, default=20_000, help="robot steps of training (4 per control tick; default 20000)")
    ap.add_argument("--train-minutes", type=float, default=1.0, help="game minutes per training match (default 1)")
    ap.add_argument("--eval-minutes", type=float, default=2.0, help="game minutes per evaluation match (default 2)")
    ap.add_argument("--eval-matches", type=int, default=2, help="evaluation matches (default 2)")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--save", help="save the trained model to this path (.zip)")
    args = ap.parse_args()

    torch.set_num_threads(1)
    # The paper's five actions, never masked (decision=None): SB3's PPO
    # would not read the masks of the shipped teams' seven.
    train_env = naosoccer.parallel_env(minutes=args.train_minutes, opponent="scripted", decision=None)
    venv = TeamVecEnv(train_env, seed=args.seed)
    model = PPO(
        "MlpPolicy",
        venv,
        n_steps=256,  # x 4 robots = 1024 samples per update
        batch_size=256,
        n_epochs=5,
        learning_rate=3e-4,
        gamma=0.99,
        ent_coef=0.01,
        seed=args.seed,
        verbose=0,
        device="cpu",
    )
    start = time.perf_counter()
    model.learn(total_timesteps=args.timesteps)
    train_secs = time.perf_counter() - start
    print(f"trained {args.timesteps} robot steps ({args.timesteps // 4} control ticks) in {train_secs:.1f} s")
    if args.save:
        model.save(args.save)
        print(f"saved the model to {args.save}")
    venv.close()

    eval_env = naosoccer.parallel_env(minutes=args.eval_minutes, opponent="scripted", decision=None)
    try:
        eval_seed = 10_000 + args.seed  # matches the policy never trained on
        summarise("PPO", evaluate(model, eval_env, args.eval_matches, eval_seed))
        summarise("random", evaluate(None, eval_env, args.eval_matches, eval_seed))
    finally:
        eval_env.close()
    return 0


if __name__ == "__main__":
    sys.exit(main())
