"""The in-process PettingZoo envs (``naosoccer.parallel_env``, ``naosoccer.env``):
PettingZoo's own API tests, the same matches as ``naosoccer match`` (state
hash for state hash), self-play, masks, the global state, render and the
options ``VectorEnv`` has."""

import json
import re
import subprocess
import warnings
from pathlib import Path

import numpy as np
import pytest
from pettingzoo.test import api_test, parallel_api_test, parallel_seed_test

pytest.importorskip("naosoccer._native", reason="the native extension is not built (scripts/wheel --in-place)")

import naosoccer  # noqa: E402
from naosoccer import VectorEnv, team_layout  # noqa: E402

TEAM = "assets/policies/ppo-team-seed1"
STAY = 4
# The ball rolls toward +x from the left half; one robot stands far away.
ROLLING = """
name = "rolling"
opponent = "idle"
duration = 3.0
[ball]
x = -1.5
y = 0.5
vx = 1.5
[[robot]]
side = "own"
player = 1
x = -2.5
y = -1.5
[[end]]
when = "goal_for"
outcome = "success"
"""


def cli_match(binary, *args):
    out = subprocess.run([binary, "match", *map(str, args), "--json"], check=True, capture_output=True, text=True)
    return json.loads(out.stdout)


def play_out(env, action):
    """Steps a reset parallel env to the end of its match, every robot
    playing ``action``; the last step's infos and the number of steps."""
    steps = 0
    while env.agents:
        _, _, _, _, infos = env.step(dict.fromkeys(env.agents, action))
        steps += 1
    return infos, steps


def test_the_parallel_api_test_passes():
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # PettingZoo warns about what it finds wrong
        parallel_api_test(naosoccer.parallel_env(minutes=0.1, seed=0), num_cycles=1000)
        parallel_api_test(naosoccer.parallel_env(team="both", obs_version=1, decision=None, minutes=0.1), num_cycles=100)
    parallel_seed_test(lambda: naosoccer.parallel_env(opponent="random", minutes=0.1), num_cycles=100)


def test_the_aec_api_test_passes():
    env = naosoccer.env(minutes=0.1, seed=0)
    api_test(env, num_cycles=100)
    # The whole match through the AEC env: the agents act in turn.
    env.reset(seed=3)
    for agent in env.agent_iter():
        obs, reward, term, trunc, info = env.last()
        mask = info["action_mask"]
        env.step(None if term or trunc else int(np.flatnonzero(mask)[-1]))
    assert not env.agents and info["ticks"] == 60
    assert env.unwrapped.tick == 60 and info["state_hash"] == env.unwrapped.state_hash()


def test_defaults_are_the_shipped_teams():
    env = naosoccer.parallel_env()
    version, decision = team_layout(TEAM)
    assert env.obs_version == version == naosoccer.TEAM_OBS_VERSION == 4
    assert env.decision == decision == dict(naosoccer.TEAM_DECISION)
    assert env.num_actions == 9
    assert env.action_names[-4:] == ("pass", "support", "approach", "defend")
    assert env.opponent == "scripted" and env.render_mode is None
    assert env.possible_agents == ["blue_0", "blue_1", "blue_2", "blue_3"]
    assert env.metadata["render_modes"] == ["rgb_array"]
    obs, infos = env.reset(seed=1)
    assert env.observation_space("blue_0").shape == (92,) and obs["blue_0"].shape == (92,)
    assert obs["blue_0"].dtype == np.float32
    assert env.action_space("blue_2").n == 9
    assert infos["blue_0"]["action_mask"].dtype == np.int8
    # `like` gives a team's layout; explicit arguments win.
    like = naosoccer.parallel_env(like="assets/policies/dqn-team-v1-seed1")
    assert (like.obs_version, like.num_actions) == (2, 5)
    like = naosoccer.parallel_env(like="assets/policies/dqn-team-seed1")
    assert (like.obs_version, like.num_actions) == (2, 9)
    paper = naosoccer.parallel_env(like=TEAM, obs_version=1, decision=None)
    assert (paper.obs_version, paper.num_actions, paper.decision) == (1, 5, None)
    older = naosoccer.parallel_env(obs_version=3)
    three, _ = older.reset(seed=1)
    assert older.observation_space("blue_0").shape == (89,) and three["blue_0"].shape == (89,)
    # Version 4 starts with version 3: the same robots see the same first 89.
    assert np.array_equal(env.reset(seed=1)[0]["blue_0"][:89], three["blue_0"])


@pytest.mark.parametrize("team,opponent", [("blue", "scripted"), ("red", "random"), ("blue", "scripted:1")])
def test_a_match_is_naosoccer_match(binary, team, opponent):
    # Robots that always stay play as `idle` does: the CLI's match, bit for bit.
    env = naosoccer.parallel_env(team=team, opponent=opponent, minutes=0.2, obs_version=2)
    env.reset(seed=17)
    infos, steps = play_out(env, STAY)
    blue, red = ("idle", opponent) if team == "blue" else (opponent, "idle")
    cli = cli_match(binary, "--seed", 17, "--minutes", 0.2, "--blue", blue, "--red", red)
    assert steps == cli["ticks"] == 120
    for info in infos.values():
        assert info["state_hash"] == cli["state_hash"] == env.state_hash()
        assert info["seed"] == 17 and info["ticks"] == 120
        assert (info["score"]["blue"], info["score"]["red"]) == (cli["score"]["blue"], cli["score"]["red"])
        assert set(info["stats"]) == {"blue", "red"}


def test_self_play_drives_both_teams(binary):
    env = naosoccer.parallel_env(team="both", minutes=0.1)
    assert env.opponent is None
    assert env.possible_agents == [f"{t}_{p}" for t in ("blue", "red") for p in range(4)]
    obs, infos = env.reset(seed=5)
    assert len(obs) == 8 and len(infos) == 8
    # Each team sees itself in its own frame: red's own x (me_x, entry 0)
    # is minus the x at which blue sees it (opp{p}_x, entry 41 + 5p).
    for p in range(4):
        assert np.isclose(obs[f"red_{p}"][0], -obs["blue_0"][41 + 5 * p])
    # The same actions give the vector env's self-play rows.
    vec = VectorEnv(1, team="both", minutes=0.1, obs_version=naosoccer.TEAM_OBS_VERSION,
                    decision=dict(naosoccer.TEAM_DECISION))
    vobs, vinfos = vec.reset(seed=5)
    np.testing.assert_array_equal(np.stack([obs[a] for a in env.agents]), vobs[0])
    rng = np.random.default_rng(2)
    while env.agents:
        acts = rng.integers(0, env.num_actions, size=8)
        obs, rewards, terms, truncs, infos = env.step(dict(zip(env.agents, acts)))
        vobs, vrew, vterm, _, vinfos = vec.step(acts[None])
        assert [rewards[a] for a in rewards] == list(vrew[0])
        if env.agents:
            np.testing.assert_array_equal(np.stack([obs[a] for a in env.agents]), vobs[0])
    assert vterm[0] and infos["red_3"]["state_hash"] == vinfos["final_info"]["state_hash"][0]
    # All eight staying is `naosoccer match --blue idle --red idle`.
    env.reset(seed=6)
    infos, _ = play_out(env, STAY)
    cli = cli_match(binary, "--seed", 6, "--minutes", 0.1, "--blue", "idle", "--red", "idle")
    assert infos["blue_0"]["state_hash"] == cli["state_hash"]


def test_masks_are_the_teams_and_in_the_infos():
    env = naosoccer.parallel_env(opponent="idle", minutes=0.1, seed=2)
    obs, infos = env.reset()
    vec = VectorEnv(1, like=TEAM, opponent="idle", minutes=0.1)
    _, vinfos = vec.reset(seed=2)
    mask = np.stack([infos[a]["action_mask"] for a in env.agents])
    # At kick-off nobody has the ball in reach: no shoot, no pass; support
    # and stay always; only the two chasers may walk.
    assert not mask[:, 3].any() and not mask[:, 5].any()
    assert mask[:, 4].all() and mask[:, 6].all() and mask[:, 0].sum() == 2
    rng = np.random.default_rng(0)
    while True:
        np.testing.assert_array_equal(mask, vinfos["action_mask"][0].astype(np.int8))
        # A random allowed action for each robot, as PettingZoo samples with a mask.
        acts = {a: env.action_space(a).sample(infos[a]["action_mask"]) for a in env.agents}
        assert all(infos[a]["action_mask"][acts[a]] == 1 for a in acts)
        obs, _, terms, _, infos = env.step(acts)
        _, _, vterm, _, vinfos = vec.step(np.array([[acts[a] for a in env.possible_agents]]))
        if not env.agents:
            break
        mask = np.stack([infos[a]["action_mask"] for a in env.agents])
    assert vterm[0]


def test_the_state_is_the_world_frame():
    env = naosoccer.parallel_env(team="both", minutes=0.1, obs_version=2, decision=None)
    assert env.state_space.shape == (70,) and len(env.state_names) == 70
    at = env.state_names.index
    obs, _ = env.reset(seed=8)
    for _ in range(25):
        obs, *_ = env.step({a: 0 for a in env.agents})
    s = env.state()
    assert s.dtype == np.float32 and env.state_space.contains(s)
    # Layout 2's ball_x (entry 19) is the world's for blue, mirrored for red;
    # me_x (entry 0) is each robot's own x.
    assert np.isclose(s[at("ball_x")], obs["blue_2"][19]) and np.isclose(s[at("ball_x")], -obs["red_1"][19])
    for p in range(4):
        assert np.isclose(s[at(f"blue{p}_x")], obs[f"blue_{p}"][0])
        assert np.isclose(s[at(f"red{p}_x")], -obs[f"red_{p}"][0])
    assert 0 < s[at("time_left")] < 1


def test_the_state_table_of_python_md_is_the_state():
    # docs/PYTHON.md lists the entries by group, `{p}` standing for players 0..3.
    doc = (Path(__file__).resolve().parents[2] / "docs" / "PYTHON.md").read_text()
    table = doc[doc.index("<!-- state:begin -->"):doc.index("<!-- state:end -->")]
    names = []
    for first, last, cells in re.findall(r"^\| (\d+)–(\d+) \| (.+?) \|", table, re.M):
        group = re.findall(r"`([^`]+)`", cells)
        expanded = [n.format(p=p) for p in range(4) for n in group] if "{p}" in cells else group
        assert len(expanded) == int(last) - int(first) + 1, cells
        names += expanded
    assert tuple(names) == naosoccer.parallel_env().state_names


def test_render_draws_the_match():
    env = naosoccer.parallel_env(render_mode="rgb_array", scenario=ROLLING, render_width=480)
    env.reset(seed=1)
    first = env.render()
    assert first.dtype == np.uint8 and first.ndim == 3 and first.shape[1:] == (480, 3)
    ball = np.all(first == [255, 150, 0], axis=-1)      # the ball's colour in the top view
    x0 = np.argwhere(ball)[:, 1].mean()
    ball_x0 = env.state()[env.state_names.index("ball_x")]
    for _ in range(10):
        env.step({a: STAY for a in env.agents})
    later = env.render()
    assert later.shape == first.shape and not np.array_equal(first, later)
    x1 = np.argwhere(np.all(later == [255, 150, 0], axis=-1))[:, 1].mean()
    ball_x1 = env.state()[env.state_names.index("ball_x")]
    assert ball_x1 > ball_x0 and x1 > x0 + 5, (x0, x1)
    # The AEC env renders the same match; no render mode, no frame.
    aec = naosoccer.env(render_mode="rgb_array", minutes=0.1)
    aec.reset(seed=1)
    assert aec.render().shape[2] == 3
    quiet = naosoccer.parallel_env(minutes=0.1)
    quiet.reset(seed=1)
    with pytest.warns(UserWarning):
        assert quiet.render() is None


def test_every_opponent_plays():
    for opponent in ["scripted", *(f"scripted:{n}" for n in range(1, 6)), "random", "idle",
                     f"ppo:{TEAM}", "dqn:assets/policies/dqn-team-seed1", "scripted:markers=1"]:
        env = naosoccer.parallel_env(opponent=opponent, minutes=0.1)
        env.reset(seed=4)
        for _ in range(3):
            env.step({a: 0 for a in env.agents})
        assert env.tick == 3, opponent


def test_a_scenario_ends_with_its_play(binary):
    scenario = "assets/scenarios/empty-goal-close.toml"
    env = naosoccer.parallel_env(scenario=scenario, obs_version=2, decision=None)
    assert env.opponent == "idle"
    env.reset(seed=21)
    infos, steps = play_out(env, 3)                            # everyone shoots
    ending = infos["blue_1"]["scenario"]
    assert ending["ending"] in ("goal_for", "ball_out", "time_up") and ending["ticks"] == steps
    assert ending["success"] == (ending["ending"] == "goal_for")
    # Staying is the CLI's scenario match with idle robots.
    env.reset(seed=21)
    infos, _ = play_out(env, STAY)
    cli = cli_match(binary, "--scenario", scenario, "--own", "blue", "--seed", 21,
                    "--blue", "idle", "--red", "idle")
    assert infos["blue_1"]["state_hash"] == cli["state_hash"]
    assert infos["blue_1"]["scenario"]["ending"] == cli["scenario"]["ending"]
    assert infos["blue_1"]["scenario"]["ticks"] == cli["scenario"]["ticks"]


def test_a_list_of_scenarios_draws_one_per_reset():
    # Each reset's match draws its scenario from its seed, as the vector
    # env's match of that seed does; the end infos name it.
    drills = {"empty-goal-close": "assets/scenarios/empty-goal-close.toml",
              "1-vs-1-keeper": "assets/scenarios/1-vs-1-keeper.toml"}
    env = naosoccer.parallel_env(scenario=list(drills.values()), obs_version=2, decision=None)
    assert env.opponent == "per scenario"
    names = set()
    for seed in range(40, 46):
        env.reset(seed=seed)
        start = env.state_hash()
        infos, steps = play_out(env, 3)                        # everyone shoots
        ending = infos["blue_1"]["scenario"]
        assert ending["ticks"] == steps and ending["name"] in drills
        names.add(ending["name"])
        alone = naosoccer.parallel_env(scenario=drills[ending["name"]], obs_version=2, decision=None)
        alone.reset(seed=seed)
        assert alone.state_hash() == start, seed
        vec = VectorEnv(1, scenario=list(drills.values()), obs_version=2)
        vec.reset(seed=seed)
        assert vec.state_hashes() == [start]
        for _ in range(steps):
            _, _, term, _, vinfos = vec.step(np.full((1, 4), 3))
        assert term[0] and vinfos["final_info"]["state_hash"][0] == infos["blue_1"]["state_hash"]
    assert names == set(drills), names
    with pytest.raises(ValueError, match="^scenario_weights: "):
        naosoccer.parallel_env(scenario=list(drills.values()), scenario_weights=[1, -1])


def test_seeds_follow_on():
    env = naosoccer.parallel_env(minutes=0.1, seed=30)
    env.reset()
    assert env.match_seed == 30
    env.reset()
    assert env.match_seed == 31
    env.reset(seed=7)
    env.reset()
    assert env.match_seed == 8
    obs_a, _ = naosoccer.parallel_env(minutes=0.1).reset(seed=9)
    obs_b, _ = naosoccer.parallel_env(minutes=0.1, seed=9).reset()
    for a in obs_a:
        np.testing.assert_array_equal(obs_a[a], obs_b[a])


def test_mistakes_are_refused():
    with pytest.raises(ValueError, match="team"):
        naosoccer.parallel_env(team="green")
    with pytest.raises(ValueError, match="render_mode"):
        naosoccer.parallel_env(render_mode="human")
    with pytest.raises(ValueError, match="unknown policy"):
        naosoccer.parallel_env(opponent="scripted-ish")
    with pytest.raises(ValueError, match="obs_version"):
        naosoccer.parallel_env(obs_version=9)
    env = naosoccer.parallel_env(minutes=0.1)
    with pytest.raises(RuntimeError, match="reset"):
        env.step({})
    env.reset(seed=0)
    with pytest.raises(ValueError, match="not one of the 9 actions"):
        env.step({"blue_0": 9})
    with pytest.raises(ValueError, match="not in play"):
        env.step({"red_0": 0})
    with pytest.raises(ValueError, match="integer"):
        env.step({"blue_0": 1.5})
    env.reset(seed=0)
    play_out(env, STAY)
    with pytest.raises(RuntimeError, match="reset"):
        env.step({})
    aec = naosoccer.env(minutes=0.1)
    aec.reset(seed=0)
    with pytest.raises(AssertionError):
        aec.step(9)
