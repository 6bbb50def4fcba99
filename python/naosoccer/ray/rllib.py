"""The PettingZoo env for RLlib (new API stack): multi-agent PPO with one
policy shared by the team's four robots.

Every env runner builds its own in-process match
(:func:`naosoccer.parallel_env`, the package's native extension, which the
runtime environment ships with the package: no server, no binary on the
nodes). python/examples/rllib_ppo.py trains with it; docs/RAY.md has its
figures.
"""

from __future__ import annotations

from typing import Any, Dict, Optional

from ray.rllib.algorithms.ppo import PPOConfig
from ray.rllib.core.rl_module.multi_rl_module import MultiRLModuleSpec
from ray.rllib.core.rl_module.rl_module import RLModuleSpec
from ray.rllib.env.wrappers.pettingzoo_env import ParallelPettingZooEnv
from ray.tune.registry import register_env

from ..parallel import ParallelMatchEnv

#: The name the env is registered under.
ENV_NAME = "naosoccer"
#: The one policy (RLModule) every robot of the team maps to.
POLICY = "team"
#: Env runner k plays match seeds (seed + k) * SEED_STRIDE onward.
SEED_STRIDE = 1_000_000


class NaoSoccerRllibEnv(ParallelPettingZooEnv):
    """RLlib's wrapper of a PettingZoo ``ParallelEnv``, with RLlib's seeds
    spread apart: RLlib resets env runner ``k`` first with ``seed + k``, and
    the env then plays the next seeds, so neighbouring runners would replay
    each other's matches; here seed ``s`` becomes match seed ``s *
    SEED_STRIDE``."""

    def reset(self, *, seed: Optional[int] = None, options: Optional[dict] = None):
        return super().reset(seed=None if seed is None else seed * SEED_STRIDE, options=options)


def make_env(config: Dict[str, Any]) -> NaoSoccerRllibEnv:
    """One team of an in-process match as an RLlib ``MultiAgentEnv``.
    ``config`` (RLlib's ``env_config``, an ``EnvContext``): ``team``,
    ``opponent``, ``minutes``, ``seed``, ``obs_version`` and ``decision``, as
    :func:`naosoccer.parallel_env` takes them (``decision`` default ``None``:
    the paper's five actions, as RLlib's default module reads no masks).
    Env runner ``k`` plays match seeds ``(seed + k) * SEED_STRIDE`` onward,
    as it does when RLlib seeds it (``config.debugging(seed=seed)``)."""
    seed: Optional[int] = config.get("seed")
    worker = getattr(config, "worker_index", 0)
    env = ParallelMatchEnv(
        team=config.get("team", "blue"),
        opponent=config.get("opponent", "scripted"),
        minutes=config.get("minutes"),
        seed=None if seed is None else (seed + worker) * SEED_STRIDE,
        obs_version=config.get("obs_version"),
        decision=config.get("decision"),
    )
    return NaoSoccerRllibEnv(env)


def ppo_config(
    *,
    env_runners: int = 2,
    minutes: float = 1.0,
    opponent: str = "scripted",
    seed: int = 0,
    train_batch: int = 4000,
    minibatch: int = 500,
    epochs: int = 4,
    lr: float = 3e-4,
) -> PPOConfig:
    """Multi-agent PPO over :func:`make_env`: the four robots share the
    policy ``"team"``; learning happens in the driver (no learner actors),
    sampling in ``env_runners`` env runner actors (0: in the driver)."""
    register_env(ENV_NAME, make_env)
    env_config = {"opponent": opponent, "minutes": minutes, "seed": seed}
    return (
        PPOConfig()
        .environment(ENV_NAME, env_config=env_config)
        .env_runners(num_env_runners=env_runners, num_envs_per_env_runner=1, rollout_fragment_length="auto")
        .learners(num_learners=0)
        .multi_agent(policies={POLICY}, policy_mapping_fn=lambda agent_id, episode, **kwargs: POLICY)
        .rl_module(rl_module_spec=MultiRLModuleSpec(rl_module_specs={POLICY: RLModuleSpec()}))
        .training(train_batch_size_per_learner=train_batch, minibatch_size=minibatch, num_epochs=epochs, lr=lr)
        .debugging(seed=seed)
    )
