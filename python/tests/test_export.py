"""``naosoccer.export_policy``: an actor trained in Python, written as a team
directory, plays in the binary exactly as its forward pass does in Python."""

import json
import subprocess

import numpy as np
import pytest

pytest.importorskip("naosoccer._native", reason="the native extension is not built (scripts/wheel --in-place)")

from naosoccer import VectorEnv, export_policy  # noqa: E402

STAY = 4


def random_actor(dims, seed):
    rng = np.random.default_rng(seed)
    return [
        (
            rng.normal(0.0, 1.0 / np.sqrt(i), (o, i)).astype(np.float32),
            rng.normal(0.0, 0.1, o).astype(np.float32),
        )
        for i, o in zip(dims, dims[1:])
    ]


def greedy(layers, obs):
    x = obs
    for k, (w, b) in enumerate(layers):
        x = x @ w.T + b
        if k < len(layers) - 1:
            x = np.tanh(x)
    return x.argmax(-1)


def test_an_exported_actor_plays_in_the_binary_as_in_python(binary, tmp_path):
    env = VectorEnv(1, team="both", minutes=0.2, seed=5)
    obs, _ = env.reset()
    layers = random_actor([obs.shape[-1], 32, 32, env.num_actions], 1)
    team = export_policy(layers, tmp_path / "team", env)
    with open(tmp_path / "team" / "config.json") as f:
        config = json.load(f)
    assert config["algo"] == "ppo" and config["obs_version"] == 2
    # Blue: the actor's most likely action, computed here; red stays, as
    # `idle` does. The binary plays the same match with the exported team.
    moves = set()
    while True:
        actions = np.full((1, 8), STAY)
        actions[0, :4] = greedy(layers, obs[0, :4])
        moves.update(actions[0, :4].tolist())
        obs, _, terminated, _, infos = env.step(actions)
        if terminated[0]:
            final = infos["final_info"]["state_hash"][0]
            break
    assert len(moves) > 1, "the actor does more than one thing"
    out = subprocess.run(
        [binary, "match", "--seed", "5", "--minutes", "0.2", "--blue", f"ppo-greedy:{team}", "--red", "idle", "--json"],
        check=True, capture_output=True, text=True,
    )
    assert json.loads(out.stdout)["state_hash"] == final


def test_a_torch_actor_exports_and_bad_shapes_are_refused(tmp_path):
    env = VectorEnv(1, minutes=0.1, seed=1, like="ppo:assets/policies/ppo-team-seed1")
    dim = env.single_observation_space.shape[-1]
    bad = random_actor([dim + 1, 8, env.num_actions], 2)
    with pytest.raises(ValueError, match="actor.l0.weight"):
        export_policy(bad, tmp_path / "bad", env)
    bad = random_actor([dim, 8, env.num_actions + 1], 2)
    with pytest.raises(ValueError, match="actions"):
        export_policy(bad, tmp_path / "bad", env)
    assert not (tmp_path / "bad" / "final.safetensors").exists()
    torch = pytest.importorskip("torch")
    nn = torch.nn
    actor = nn.Sequential(nn.Linear(dim, 16), nn.Tanh(), nn.Linear(16, env.num_actions))
    path = export_policy(actor, tmp_path / "torch", env)
    with open(f"{path}/config.json") as f:
        config = json.load(f)
    assert config["obs_version"] == 4 and config["ppo"]["decision"]["pass"] is True
    with pytest.raises(ValueError, match="Tanh"):
        export_policy(nn.Sequential(nn.Linear(dim, 16), nn.ReLU(), nn.Linear(16, env.num_actions)), tmp_path / "relu", env)
