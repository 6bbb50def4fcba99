"""PPO in one file, in the style of CleanRL's ppo.py, on naosoccer.VectorEnv.

One actor-critic is shared by the four robots of the blue team: every robot
of every match is one sample (its own observation, reward and action mask),
so 8 matches give 32 samples a control tick. The matches run inside this
process (no server, no sockets). After a wall-clock budget the actor is
written as a team directory in the shipped teams' format with
``naosoccer.export_policy`` and scored by ``naosoccer eval``, the command
that scores the shipped teams, so the numbers compare with theirs.

    .venv/bin/python python/examples/cleanrl_ppo.py --seconds 300

Needs torch (the project's set-up installs it into .venv). docs/PYTHON.md,
"A PPO in one file", has a measured run.
"""

import argparse
import json
import os
import subprocess
import sys
import time

import numpy as np
import torch
import torch.nn as nn

# From a checkout the package is the one beside this file; installed, it is found anyway.
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
import naosoccer  # noqa: E402


def parse_args():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--seconds", type=float, default=300.0, help="wall-clock training budget (default 300)")
    p.add_argument("--num-matches", type=int, default=8, help="matches stepped together (default 8)")
    p.add_argument("--num-steps", type=int, default=128, help="control ticks per rollout (default 128)")
    p.add_argument("--minutes", type=float, default=2.0, help="length of a training match (default 2)")
    p.add_argument("--opponent", default="random", help="the team trained against (any policy spec; default random)")
    p.add_argument("--seed", type=int, default=1, help="seed of torch and of the matches (default 1)")
    p.add_argument("--lr", type=float, default=3e-4)
    p.add_argument("--gamma", type=float, default=0.99)
    p.add_argument("--gae-lambda", type=float, default=0.95)
    p.add_argument("--update-epochs", type=int, default=4)
    p.add_argument("--minibatches", type=int, default=4)
    p.add_argument("--clip", type=float, default=0.2)
    p.add_argument("--ent-coef", type=float, default=0.01)
    p.add_argument("--vf-coef", type=float, default=0.5)
    p.add_argument("--hidden", type=int, default=64)
    p.add_argument("--out", default="runs/cleanrl-team", help="team directory written at the end (default runs/cleanrl-team)")
    p.add_argument("--eval-matches", type=int, default=20, help="matches per opponent in the final eval, 0: none (default 20)")
    p.add_argument("--eval-against", default="random,scripted:1,scripted",
                   help="comma-separated opponents of the final eval (default random,scripted:1,scripted)")
    p.add_argument("--eval-minutes", type=float, default=None, help="length of an eval match (default: the configuration's)")
    return p.parse_args()


def mlp(inputs, hidden, outputs, last_std):
    def layer(i, o, std):
        lin = nn.Linear(i, o)
        nn.init.orthogonal_(lin.weight, std)
        nn.init.constant_(lin.bias, 0.0)
        return lin

    return nn.Sequential(
        layer(inputs, hidden, np.sqrt(2)), nn.Tanh(),
        layer(hidden, hidden, np.sqrt(2)), nn.Tanh(),
        layer(hidden, outputs, last_std),
    )


class Agent(nn.Module):
    def __init__(self, obs_dim, actions, hidden):
        super().__init__()
        # Linear and Tanh layers only: export_policy writes exactly these.
        self.actor = mlp(obs_dim, hidden, actions, 0.01)
        self.critic = mlp(obs_dim, hidden, 1, 1.0)

    def value(self, x):
        return self.critic(x).squeeze(-1)

    def act(self, x, mask, action=None):
        logits = self.actor(x).masked_fill(~mask, -1e9)
        dist = torch.distributions.Categorical(logits=logits)
        if action is None:
            action = dist.sample()
        return action, dist.log_prob(action), dist.entropy(), self.value(x)


def evaluate(out, opponents, matches, minutes, seed):
    """`naosoccer eval` against each opponent, both sides; returns its JSON."""
    results = {}
    for opp in opponents:
        cmd = [naosoccer.find_binary(), "eval", "--blue", f"ppo:{out}", "--red", opp,
               "--matches", str(matches), "--both-sides", "--seed", str(seed), "--json"]
        if minutes is not None:
            cmd += ["--minutes", str(minutes)]
        text = subprocess.run(cmd, check=True, capture_output=True, text=True).stdout
        results[opp] = json.loads(text)
    return results


def main():
    args = parse_args()
    torch.manual_seed(args.seed)
    torch.set_num_threads(1)
    env = naosoccer.VectorEnv(num_matches=args.num_matches, opponent=args.opponent,
                              minutes=args.minutes, seed=args.seed,
                              decision={"persist": 1, "mask_shoot": True}, threads=1)
    m, robots = args.num_matches, env.single_observation_space.shape[0]
    obs_dim, n_act = env.single_observation_space.shape[-1], env.num_actions
    n = m * robots                                   # samples a tick
    agent = Agent(obs_dim, n_act, args.hidden)
    opt = torch.optim.Adam(agent.parameters(), lr=args.lr, eps=1e-5)

    S = args.num_steps
    obs_buf = torch.zeros((S, n, obs_dim))
    mask_buf = torch.zeros((S, n, n_act), dtype=torch.bool)
    act_buf = torch.zeros((S, n), dtype=torch.long)
    logp_buf = torch.zeros((S, n))
    rew_buf = torch.zeros((S, n))
    done_buf = torch.zeros((S, n))
    val_buf = torch.zeros((S, n))

    o, infos = env.reset(seed=args.seed)
    next_obs = torch.as_tensor(o.reshape(n, obs_dim))
    next_mask = torch.as_tensor(infos["action_mask"].reshape(n, n_act))
    next_done = torch.zeros(n)
    start, ticks, updates = time.monotonic(), 0, 0
    goals_for = goals_against = ended = 0
    while time.monotonic() - start < args.seconds:
        for t in range(S):
            obs_buf[t], mask_buf[t], done_buf[t] = next_obs, next_mask, next_done
            with torch.no_grad():
                action, logp, _, value = agent.act(next_obs, next_mask)
            act_buf[t], logp_buf[t], val_buf[t] = action, logp, value
            o, r, term, trunc, infos = env.step(action.numpy().reshape(m, robots))
            ticks += m
            rew_buf[t] = torch.as_tensor(r.reshape(n))
            done = np.repeat(term | trunc, robots)
            next_obs = torch.as_tensor(o.reshape(n, obs_dim))
            next_mask = torch.as_tensor(infos["action_mask"].reshape(n, n_act))
            next_done = torch.as_tensor(done, dtype=torch.float32)
            if "final_info" in infos:
                for i in np.flatnonzero(infos["_final_info"]):
                    score = infos["final_info"]["score"]      # arrays over the slots
                    goals_for += int(score["blue"][i])
                    goals_against += int(score["red"][i])
                    ended += 1

        # Generalised advantage estimation; a match that ended is not bootstrapped.
        with torch.no_grad():
            next_value = agent.value(next_obs)
            adv = torch.zeros_like(rew_buf)
            last = torch.zeros(n)
            for t in reversed(range(S)):
                nonterminal = 1.0 - (next_done if t == S - 1 else done_buf[t + 1])
                nv = next_value if t == S - 1 else val_buf[t + 1]
                delta = rew_buf[t] + args.gamma * nv * nonterminal - val_buf[t]
                last = delta + args.gamma * args.gae_lambda * nonterminal * last
                adv[t] = last
            ret = adv + val_buf

        b_obs, b_mask = obs_buf.reshape(-1, obs_dim), mask_buf.reshape(-1, n_act)
        b_act, b_logp = act_buf.reshape(-1), logp_buf.reshape(-1)
        b_adv, b_ret = adv.reshape(-1), ret.reshape(-1)
        batch = b_obs.shape[0]
        mb = batch // args.minibatches
        for _ in range(args.update_epochs):
            perm = torch.randperm(batch)
            for k in range(0, batch, mb):
                idx = perm[k:k + mb]
                _, logp, entropy, value = agent.act(b_obs[idx], b_mask[idx], b_act[idx])
                ratio = (logp - b_logp[idx]).exp()
                a = b_adv[idx]
                a = (a - a.mean()) / (a.std() + 1e-8)
                pg = torch.max(-a * ratio, -a * ratio.clamp(1 - args.clip, 1 + args.clip)).mean()
                v_loss = 0.5 * ((value - b_ret[idx]) ** 2).mean()
                loss = pg - args.ent_coef * entropy.mean() + args.vf_coef * v_loss
                opt.zero_grad()
                loss.backward()
                nn.utils.clip_grad_norm_(agent.parameters(), 0.5)
                opt.step()
        updates += 1
        if updates % 10 == 0:
            el = time.monotonic() - start
            per = f"goals {goals_for / max(ended, 1):.2f} : {goals_against / max(ended, 1):.2f} a match over {ended} matches"
            print(f"{el:6.0f} s  {ticks:>9,} match ticks ({ticks / el:,.0f}/s)  update {updates}  {per}", flush=True)

    elapsed = time.monotonic() - start
    print(f"trained {ticks:,} match ticks ({ticks * robots:,} robot steps) in {elapsed:.0f} s, {updates} updates")
    os.makedirs(os.path.dirname(os.path.abspath(args.out)), exist_ok=True)
    naosoccer.export_policy(agent.actor, args.out, env)
    print(f"wrote the team to {args.out}: naosoccer eval --blue ppo:{args.out} ...")
    if args.eval_matches > 0:
        opponents = [x for x in args.eval_against.split(",") if x]
        for opp, d in evaluate(args.out, opponents, args.eval_matches, args.eval_minutes, 1234).items():
            b = d["blue"]
            print(f"vs {opp:<12} W/D/L {b['wins']}/{b['draws']}/{b['losses']}  "
                  f"goals {b['goals']['mean']:.2f} : {d['red']['goals']['mean']:.2f} a match")


if __name__ == "__main__":
    main()
