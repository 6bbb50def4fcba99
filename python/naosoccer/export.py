"""``export_policy``: a PPO actor trained in Python on a :class:`VectorEnv`
written as a team directory in the shipped format (``config.json`` and
``final.safetensors``), so that ``naosoccer eval --blue ppo:DIR``, ``match``,
``league``, ``server --fill`` and ``client --policy`` play it exactly as they
play the shipped teams, and Python results compare with theirs.
"""

from __future__ import annotations

import os
from typing import Any, List, Sequence, Tuple, Union

import numpy as np

Layers = Sequence[Tuple[Any, Any]]


def _layers_of_module(actor: Any) -> List[Tuple[np.ndarray, np.ndarray]]:
    """The ``nn.Linear`` layers of a torch module made of ``Linear`` and
    ``Tanh`` only (``nn.Sequential(Linear, Tanh, Linear, Tanh, Linear)``, the
    shipped teams' actor), in order."""
    import torch.nn as nn  # only for torch modules; numpy layers need no torch

    parts = [m for m in actor.modules() if not list(m.children())]
    kinds = [type(m).__name__ for m in parts]
    ok = (
        len(parts) % 2 == 1
        and all(isinstance(m, nn.Linear) for m in parts[0::2])
        and all(isinstance(m, nn.Tanh) for m in parts[1::2])
    )
    if not ok:
        raise ValueError(
            "export_policy reads actors made of nn.Linear layers with nn.Tanh between them "
            f"and a Linear last (the shipped teams' shape); this one is {kinds}"
        )
    out = []
    for m in parts[0::2]:
        if m.bias is None:
            raise ValueError("export_policy needs nn.Linear layers with a bias")
        out.append(
            (
                m.weight.detach().to("cpu").float().numpy(),
                m.bias.detach().to("cpu").float().numpy(),
            )
        )
    return out


def export_policy(actor: Union[Any, Layers], directory: Union[str, os.PathLike], env: Any) -> str:
    """Write ``actor`` as a PPO team directory that ``naosoccer`` plays.

    ``actor``: a torch module of ``nn.Linear`` layers with ``nn.Tanh`` between
    them (the last layer's outputs are the action logits), or a sequence of
    ``(weight, bias)`` arrays, ``weight`` shaped ``(outputs, inputs)`` as
    ``nn.Linear`` holds it. ``env``: the :class:`VectorEnv` it was trained on;
    its observation layout (``obs_version``, the field scale, the match
    length) and its action set (``decision``) go into ``config.json``, so the
    team sees and acts in play as it did in training. The first layer must
    read ``env.single_observation_space.shape[-1]`` values and the last give
    ``env.num_actions`` logits. The directory is created; its
    ``config.json`` and ``final.safetensors`` are replaced; the team is loaded
    back before this returns, so an error here means nothing playable was
    written. Returns the directory as a string (``ppo:`` + it is its spec).

    In play the team samples its action from the softmax of the logits
    (``ppo:DIR``) or takes the largest (``ppo-greedy:DIR``).
    """
    native = getattr(env, "_native", None)
    if native is None or not hasattr(native, "write_team"):
        raise TypeError("export_policy needs the naosoccer.VectorEnv the actor was trained on")
    if hasattr(actor, "modules"):
        layers = _layers_of_module(actor)
    else:
        layers = [
            (np.asarray(w, dtype=np.float32), np.asarray(b, dtype=np.float32)) for w, b in actor
        ]
    for i, (w, b) in enumerate(layers):
        if w.ndim != 2 or b.ndim != 1:
            raise ValueError(
                f"layer {i}: weight must be 2-D (outputs, inputs) and bias 1-D, "
                f"got shapes {w.shape} and {b.shape}"
            )
    path = os.fspath(directory)
    native.write_team(
        path,
        [(np.ascontiguousarray(w), np.ascontiguousarray(b)) for w, b in layers],
    )
    return path
