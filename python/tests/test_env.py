"""NaoSoccerParallelEnv against a real server it starts itself."""

import json
import subprocess
import threading
from pathlib import Path

import numpy as np
import pytest
from pettingzoo.test import parallel_api_test, parallel_seed_test

from naosoccer import FEATURE_NAMES, NaoSoccerError, NaoSoccerParallelEnv, RewardWeights, protocol, team_rewards

TRAIN_TOML = Path(__file__).resolve().parents[2] / "assets" / "train.toml"

STAY = protocol.ACTION_INDEX["stay"]


@pytest.fixture
def make_env(binary):
    envs = []

    def make(**kw):
        env = NaoSoccerParallelEnv(binary=binary, **kw)
        envs.append(env)
        return env

    yield make
    for env in envs:
        env.close()


def test_parallel_api(make_env):
    env = make_env(minutes=0.2, seed=1)
    parallel_api_test(env, num_cycles=1000)
    assert env.agents == [] and env.possible_agents == [f"blue_{p}" for p in range(4)]


def test_parallel_seed(make_env):
    # Two envs, each with its own server, seeded alike, play alike.
    parallel_seed_test(lambda: make_env(minutes=0.2))


def play(env, seed, steps, policy):
    obs, _ = env.reset(seed=seed)
    trace = [np.stack([obs[a] for a in env.possible_agents])]
    rewards = []
    for t in range(steps):
        obs, rew, term, trunc, info = env.step({a: policy(t, p) for p, a in enumerate(env.agents)})
        trace.append(np.stack([obs[a] for a in env.possible_agents]))
        rewards.append([rew[a] for a in env.possible_agents])
    return np.stack(trace), np.array(rewards)


def play_to_end(env, seed, policy):
    """Plays a whole match; per tick the rewards and the raw observation
    (player 0's, as the server sent it) before and after."""
    env.reset(seed=seed)
    ticks = []
    t = 0
    while env.agents:
        before = env._last
        _, rew, _, _, _ = env.step({a: policy(t, p) for p, a in enumerate(env.agents)})
        ticks.append(([rew[a] for a in env.possible_agents], before, env._last if env.agents else None))
        t += 1
    return ticks


def wander(t, p):
    return (t // 5 + p) % 4  # forward, turns and shots, never stay


def test_server_rewards_agree_with_the_client_side_terms(make_env):
    # The default configuration's reward as the server sends it (float32)
    # and as team_rewards computes it from the observations (float64).
    sent = play_to_end(make_env(minutes=0.2), 3, wander)
    local = play_to_end(make_env(minutes=0.2, reward_weights=RewardWeights()), 3, wander)
    assert len(sent) == len(local) == 120
    for t, ((a, _, _), (b, _, _)) in enumerate(zip(sent[:-1], local[:-1])):
        assert a == pytest.approx(b, abs=1e-5), f"tick {t}"
    # The last tick: no observation follows, so the client side pays only
    # the goal term; the server's match_end carries the whole reward.
    assert local[-1][0] == [0.0] * 4
    assert all(r != 0.0 for r in sent[-1][0])


def restarted(before, after):
    """Whether a set play (kick-off, kick-in, goal or corner kick) was
    awarded during the tick between two observations."""
    new, old = after.get("set_play"), before.get("set_play")
    if new is None:
        return False
    return old is None or new["kind"] != old["kind"] or new["ticks_left"] >= old["ticks_left"]


def test_server_rewards_follow_the_servers_match_configuration(make_env):
    # assets/train.toml (the shipped policies' training reward) pays
    # `progress`, potential-based shaping outside the log (protocol 1.2): the
    # ball's x in the team frame, between the state a tick starts from and
    # the state its physics reaches, before any restart. The server's
    # rewards carry it; observations show it on ticks without a restart.
    env = make_env(minutes=0.2, server_args=["--match-config", str(TRAIN_TOML)])
    w = RewardWeights(goal=10.0, close=0.02, control=0.02, opponent_control=0.02)
    moved = 0
    for t, (rew, before, after) in enumerate(play_to_end(env, 3, wander)):
        if after is None or after["score"] != before["score"]:
            continue  # the last tick and goal ticks
        if restarted(before, after):
            continue  # a restart put the ball back: no observation shows where the physics left it
        dx = after["ball"]["x"] - before["ball"]["x"]
        moved += abs(dx) > 1e-3
        expected = [r + 1.0 * dx for r in team_rewards(w, after, 0, 0)]
        assert rew == pytest.approx(expected, abs=1e-4), f"tick {t}"
    assert moved > 10, "the ball moved, so progress was paid"


def test_seeded_resets_repeat(make_env):
    env = make_env(minutes=0.5)
    policy = lambda t, p: (t // 7 + p) % 5  # noqa: E731
    a, ra = play(env, 11, 40, policy)
    assert env.joined["seed"] == 11
    b, rb = play(env, 11, 40, policy)
    assert a.tobytes() == b.tobytes(), "same seed and actions must give the same observations"
    assert ra.tobytes() == rb.tobytes()
    c, _ = play(env, 12, 40, policy)
    assert a.tobytes() != c.tobytes(), "another seed gives another match (gait noise)"
    # The kick-off is one of two formations: who kicks off is a coin toss
    # seeded by the match seed (protocol 1.2).
    firsts = {a[0].tobytes(), c[0].tobytes()}
    for seed in (13, 14, 15, 16):
        d, _ = play(env, seed, 1, policy)
        firsts.add(d[0].tobytes())
    assert len(firsts) == 2, f"{len(firsts)} different kick-offs over six seeds"
    env.reset()
    assert env.joined["seed"] == 17, "a reset without a seed plays the next seed"


# Seed 4 over one minute has red score (on the build this was written on);
# the comparison does not depend on it, the goal just makes it less trivial.
@pytest.mark.parametrize("seed,minutes", [(4, 1.0), (8, 0.5)])
def test_episode_matches_the_cli_match(make_env, binary, seed, minutes):
    env = make_env(minutes=minutes, opponent="scripted")
    env.reset(seed=seed)
    steps = 0
    conceded = []
    while env.agents:
        obs, rew, term, trunc, infos = env.step({a: STAY for a in env.agents})
        steps += 1
        for e in infos["blue_0"]["events"]:
            if e["kind"] == "goal":
                conceded.append(e["side"] == "opponent")
                assert all(r < 0 for r in rew.values()) == (e["side"] == "opponent")
    assert all(term.values()) and not any(trunc.values())
    end = infos["blue_0"]["match_end"]
    cli = json.loads(
        subprocess.run(
            [binary, "match", "--seed", str(seed), "--blue", "idle", "--red", "scripted", "--minutes", str(minutes), "--json"],
            check=True,
            capture_output=True,
            text=True,
            timeout=300,
        ).stdout
    )
    assert end["tick"] == cli["ticks"] == steps
    assert end["score"] == cli["score"]
    assert end["misses"]["blue"] == [0, 0, 0, 0]
    for team in ("blue", "red"):
        for key, value in cli["stats"][team].items():
            assert end["stats"][team][key] == value, (team, key)
    assert infos["blue_0"]["score"] == {"own": cli["score"]["blue"], "opponent": cli["score"]["red"]}
    assert sorted(conceded) == [False] * cli["score"]["blue"] + [True] * cli["score"]["red"]
    final = obs["blue_0"]
    assert final[FEATURE_NAMES.index("time_left")] == 0.0
    assert final[FEATURE_NAMES.index("score_opponent")] == pytest.approx(0.1 * cli["score"]["red"])


def test_bad_action_raises_the_server_error(make_env):
    env = make_env(minutes=0.2)
    env.reset(seed=1)
    env.step({a: STAY for a in env.agents})
    with pytest.raises(NaoSoccerError) as e:
        env.step({"blue_0": 7, "blue_1": STAY, "blue_2": STAY, "blue_3": STAY})
    assert e.value.code == "invalid_argument"
    assert "7" in e.value.message  # the server names the value it rejected
    with pytest.raises(RuntimeError):
        env.step({a: STAY for a in env.possible_agents})
    # A reset recovers: a fresh match.
    obs, infos = env.reset(seed=1)
    assert infos["blue_0"]["tick"] == 0 and set(obs) == set(env.possible_agents)


def test_two_client_envs_play_each_other(make_env):
    blue = make_env(minutes=0.1, opponent="client")
    created = threading.Event()
    box = {}

    def on_match(match_id):
        box["id"] = match_id
        created.set()

    blue.on_match = on_match
    red = NaoSoccerParallelEnv(
        team="red", host=blue.host, port=blue.port, token=blue.server.tokens["red"], opponent="client"
    )
    results = {}

    def run(env, key, **reset_kw):
        try:
            env.reset(**reset_kw)
            n = 0
            while env.agents:
                *_, infos = env.step({a: (n + i) % 5 for i, a in enumerate(env.agents)})
                n += 1
            results[key] = (n, infos[env.possible_agents[0]])
        except BaseException as e:  # surfaced below
            results[key] = e

    t = threading.Thread(target=run, args=(blue, "blue"), kwargs={"seed": 4})
    t.start()
    assert created.wait(timeout=60)
    run(red, "red", options={"match_id": box["id"]})
    t.join(timeout=120)
    red.close()
    for key in ("blue", "red"):
        assert not isinstance(results[key], BaseException), results[key]
    (nb, ib), (nr, ir) = results["blue"], results["red"]
    assert nb == nr == 60
    assert ib["match_end"] == ir["match_end"]
    assert ib["score"] == {"own": ir["score"]["opponent"], "opponent": ir["score"]["own"]}


def test_joins_a_running_servers_match_without_the_admin_token(binary):
    from naosoccer import LocalServer

    args = ["--seed", "21", "--start-players", "4", "--minutes", "0.1", "--fill", "idle"]
    with LocalServer(binary, args, matches=1) as srv:
        env = NaoSoccerParallelEnv(host=srv.host, port=srv.port, token=srv.tokens["blue"])
        try:
            obs, infos = env.reset()
            assert env.joined["seed"] == 21 and env.match_id == 1
            n = 0
            while env.agents:
                *_, infos = env.step({a: 0 for a in env.agents})
                n += 1
            assert n == 60 and infos["blue_0"]["stats"]["red"]["shots"] == 0  # idle fill never kicks
            with pytest.raises(NaoSoccerError) as e:
                env.reset()  # the only match has finished
            assert e.value.code in ("not_found", "failed_precondition")
        finally:
            env.close()


def test_infos_carry_the_servers_events(make_env):
    # Protocol 1.2: the referee's events of each tick come with the
    # observation after it (the last tick's with match_end); the env passes
    # them on with team-relative `side` and `player` added.
    env = make_env(minutes=0.5, opponent="scripted")
    obs, infos = env.reset(seed=5)
    assert infos["blue_0"]["events"] == [], "no tick led to the kick-off"
    steps = []
    t = 0
    while env.agents:
        obs, rew, term, trunc, infos = env.step({a: wander(t, p) for p, a in enumerate(env.agents)})
        steps.append((infos["blue_0"], obs["blue_0"].copy()))
        t += 1
    end = steps[-1][0]["match_end"]
    assert len(steps) == end["tick"] == 300
    kinds = set()
    for k, (info, vec) in enumerate(steps):
        for e in info["events"]:
            kinds.add(e["kind"])
            assert e["tick"] == k, (k, e)  # played on step k's tick
            if "robot" in e:
                team = protocol.TEAMS[e["robot"] // 4]
                assert e["side"] == ("own" if team == "blue" else "opponent")
                assert e["player"] == e["robot"] % 4
            if e["kind"] == "fall" and e["side"] == "own" and k + 1 < len(steps):
                assert vec[FEATURE_NAMES.index(f"own{e['player']}_fallen")] == 1.0
    first = steps[0][0]["events"]
    assert first[0]["kind"] == "kick_off" and first[0]["tick"] == 0
    assert steps[-1][0]["events"][-1] == {"kind": "end", "tick": 299}
    assert [e["kind"] for e in end["events"]] == [e["kind"] for e in steps[-1][0]["events"]]
    goals = [e for info, _ in steps for e in info["events"] if e["kind"] == "goal"]
    assert sum(e["side"] == "own" for e in goals) == end["score"]["blue"]
    assert sum(e["side"] == "opponent" for e in goals) == end["score"]["red"]
    kicks = sum(e["kind"] == "kick" for info, _ in steps for e in info["events"])
    assert kicks == end["stats"]["blue"]["shots"] + end["stats"]["red"]["shots"]
    assert {"kick_off", "kick", "end"} <= kinds


def test_positions_are_scaled_by_the_announced_pitch(make_env, tmp_path):
    # Protocol 1.2: joined announces the pitch, so the env normalises by the
    # server's field without being told it.
    cfg = tmp_path / "long.toml"
    cfg.write_text("[sim]\nfield_length = 7.5\nfield_width = 5.0\n")
    env = make_env(minutes=0.1, server_args=["--match-config", str(cfg)])
    obs, _ = env.reset(seed=2)
    assert env.joined["pitch"]["field_length"] == 7.5
    assert env.joined["pitch"]["frame"] == "team"
    own = env._last["own"]
    vec = obs["blue_0"]
    for p in range(4):
        assert vec[FEATURE_NAMES.index(f"own{p}_x")] == pytest.approx(own[p]["x"] / 3.75, abs=1e-6)
        assert vec[FEATURE_NAMES.index(f"own{p}_y")] == pytest.approx(own[p]["y"] / 2.5, abs=1e-6)


SCENARIO = Path(__file__).resolve().parents[2] / "assets" / "scenarios" / "empty-goal-close.toml"


@pytest.mark.parametrize("team,as_text", [("blue", False), ("red", True)])
def test_a_scenario_episode_is_the_cli_scenario_match(make_env, binary, team, as_text):
    # Protocol 1.5: the env's matches start from the scenario, its team the
    # scenario's own; standing still, the play ends as the CLI's does.
    scenario = SCENARIO.read_text() if as_text else str(SCENARIO)
    env = make_env(team=team, opponent="idle", scenario=scenario)
    env.reset(seed=5)
    steps = 0
    while env.agents:
        obs, rew, term, trunc, infos = env.step({a: STAY for a in env.agents})
        steps += 1
    assert all(term.values()) and not any(trunc.values())
    end = infos[f"{team}_0"]["match_end"]
    cli = json.loads(
        subprocess.run(
            [binary, "match", "--scenario", str(SCENARIO), "--own", team, "--seed", "5",
             "--blue", "idle", "--red", "idle", "--json"],
            check=True,
            capture_output=True,
            text=True,
            timeout=300,
        ).stdout
    )
    assert end["state_hash"] == cli["state_hash"]
    s = infos[f"{team}_0"]["scenario"]
    assert s == end["scenario"]
    assert (s["name"], s["team"]) == ("empty-goal-close", team)
    assert (s["ending"], s["success"], s["ticks"]) == (cli["scenario"]["ending"], cli["scenario"]["success"], cli["scenario"]["ticks"])
    assert s["ticks"] == steps


def test_a_scenario_needs_the_admin_token(binary):
    with pytest.raises(ValueError, match="admin_token"):
        NaoSoccerParallelEnv(host="127.0.0.1", port=1, token="t", scenario=str(SCENARIO))
    with pytest.raises(FileNotFoundError):
        NaoSoccerParallelEnv(host="127.0.0.1", port=1, token="t", scenario="no-such-drill.toml")
