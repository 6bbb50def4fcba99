"""The in-process vector env (``naosoccer.VectorEnv``, the native extension):
spaces and shapes, the same matches as ``naosoccer match`` (state hash for
state hash), auto-reset in the same step, action masks, opponents, the same
matches whatever the number of threads, and threads that end with the env."""

import gc
import json
import os
import subprocess

import numpy as np
import pytest

pytest.importorskip("naosoccer._native", reason="the native extension is not built (scripts/wheel --in-place)")

from naosoccer import VectorEnv  # noqa: E402

TEAM = "assets/policies/ppo-team-seed1"
STAY = 4


def cli_match(binary, seed, minutes, blue, red):
    out = subprocess.run(
        [binary, "match", "--seed", str(seed), "--minutes", str(minutes), "--blue", blue, "--red", red, "--json"],
        check=True, capture_output=True, text=True,
    )
    return json.loads(out.stdout)


def play_to_end(env, action):
    """Steps until every slot's first match ended; the final infos by slot."""
    finals = {}
    steps = 0
    while len(finals) < env.num_envs:
        _, rewards, term, trunc, infos = env.step(np.full((env.num_envs, env.robots), action))
        assert rewards.shape == (env.num_envs, env.robots) and not trunc.any()
        steps += 1
        for i in np.flatnonzero(term):
            assert infos["_final_info"][i] and infos["_final_obs"][i]
            finals.setdefault(int(i), {
                "state_hash": infos["final_info"]["state_hash"][i],
                "seed": int(infos["final_info"]["seed"][i]),
                "ticks": int(infos["final_info"]["ticks"][i]),
                "score": (int(infos["final_info"]["score"]["blue"][i]), int(infos["final_info"]["score"]["red"][i])),
                "final_obs": infos["final_obs"][i],
            })
    return finals, steps


def test_spaces_and_shapes():
    env = VectorEnv(3, opponent="idle", minutes=0.1, seed=1)
    obs, infos = env.reset()
    assert obs.shape == (3, 4, 75) and obs.dtype == np.float32
    assert env.single_observation_space.shape == (4, 75)
    assert env.observation_space.shape == (3, 4, 75)
    assert list(env.single_action_space.nvec) == [5] * 4
    assert env.action_space.shape == (3, 4)
    assert infos["action_mask"].shape == (3, 4, 5) and infos["action_mask"].all()
    assert env.agents == ["blue_0", "blue_1", "blue_2", "blue_3"]
    assert env.observation_space.contains(obs)
    both = VectorEnv(2, team="both", minutes=0.1, obs_version=1)
    obs, infos = both.reset(seed=3)
    assert obs.shape == (2, 8, 48) and both.agents[4] == "red_0"


@pytest.mark.parametrize("team,opponent", [("blue", "scripted"), ("red", "scripted"), ("blue", "random")])
def test_matches_are_naosoccer_match(binary, team, opponent):
    # Robots that always stay play as `idle` does: the same match as the
    # CLI's, bit for bit, for every slot's seed.
    env = VectorEnv(2, team=team, opponent=opponent, minutes=0.2, seed=11)
    env.reset()
    finals, steps = play_to_end(env, STAY)
    assert steps == 120
    for i in range(2):
        blue, red = ("idle", opponent) if team == "blue" else (opponent, "idle")
        cli = cli_match(binary, 11 + i, 0.2, blue, red)
        assert finals[i]["seed"] == 11 + i
        assert finals[i]["state_hash"] == cli["state_hash"], (team, opponent, i)
        assert finals[i]["score"] == (cli["score"]["blue"], cli["score"]["red"])
        assert finals[i]["ticks"] == cli["ticks"]


def test_finished_matches_restart_in_the_same_step():
    env = VectorEnv(2, opponent="scripted", minutes=0.1, seed=5)
    env.reset()
    finals, _ = play_to_end(env, 0)
    # Each slot's next match: seed + slot + num_matches, at its kick-off,
    # the observation a fresh reset with that seed gives.
    assert env.seeds() == [7, 8] and env.ticks() == [0, 0]
    obs, _, _, _, _ = env.step(np.full((2, 4), STAY))
    fresh = VectorEnv(2, opponent="scripted", minutes=0.1)
    obs0, _ = fresh.reset(seed=7)
    after, _, _, _, _ = fresh.step(np.full((2, 4), STAY))
    np.testing.assert_array_equal(obs[0], after[0])
    assert finals[0]["final_obs"].shape == (4, 75)


def test_same_seed_same_steps():
    runs = []
    for _ in range(2):
        env = VectorEnv(2, opponent="random", minutes=0.1, seed=9)
        obs, _ = env.reset()
        rng = np.random.default_rng(0)
        trace = [obs]
        for _ in range(40):
            obs, r, *_ = env.step(rng.integers(0, 5, size=(2, 4)))
            trace += [obs, r]
        runs.append(trace)
    for a, b in zip(*runs):
        np.testing.assert_array_equal(a, b)


def run_trace(threads, steps):
    """Everything ``steps`` steps of random actions return, and the state
    hashes after each."""
    env = VectorEnv(3, opponent="scripted", minutes=0.2, seed=13, threads=threads, like=TEAM)
    assert env.threads == threads
    obs, infos = env.reset()
    trace = [obs, infos["action_mask"]]
    rng = np.random.default_rng(5)
    for _ in range(steps):
        obs, rewards, term, _, infos = env.step(rng.integers(0, env.num_actions, size=(3, 4)))
        trace += [obs, rewards, term, infos["action_mask"], env.state_hashes()]
        if term.any():
            trace += [infos["final_obs"][term].tolist(), infos["final_info"]["state_hash"][term].tolist(),
                      infos["final_info"]["seed"][term].tolist()]
    env.close()
    return trace


def test_threads_do_not_change_the_matches():
    # 300 steps of 0.2-minute matches: every slot restarts twice. One
    # thread or several, the same arrays and the same state hashes.
    one = run_trace(1, 300)
    assert sum(isinstance(t, np.ndarray) and t.dtype == bool and t.ndim == 1 and t.any() for t in one) == 2
    for threads in (2, 3):
        other = run_trace(threads, 300)
        assert len(other) == len(one)
        for k, (a, b) in enumerate(zip(one, other)):
            np.testing.assert_array_equal(a, b, err_msg=f"threads {threads}, entry {k}")


def stepping_threads():
    """The env threads alive in this process (Linux names them
    ``naosoccer-step-N``, cut to 15 characters)."""
    names = []
    for tid in os.listdir("/proc/self/task"):
        try:
            with open(f"/proc/self/task/{tid}/comm") as f:
                names.append(f.read().strip())
        except FileNotFoundError:  # a thread that ended meanwhile
            pass
    return sum(n.startswith("naosoccer-step") for n in names)


@pytest.mark.skipif(not os.path.isdir("/proc/self/task"), reason="counts threads through Linux's /proc")
def test_threads_end_with_the_env():
    gc.collect()  # envs other tests dropped in reference cycles: gone now, not during the test
    before = stepping_threads()
    env = VectorEnv(4, opponent="idle", minutes=0.1, seed=1, threads=3)
    assert stepping_threads() == before, "the threads start with the first reset"
    env.reset()
    env.step(np.full((4, 4), STAY))
    assert stepping_threads() == before + 2, "the caller's thread steps too"
    env.close()
    assert stepping_threads() == before
    with pytest.raises(RuntimeError, match="closed"):
        env.step(np.full((4, 4), STAY))
    env.close()  # a second close does nothing
    # An env that is dropped without close() stops its threads too.
    env = VectorEnv(4, opponent="idle", minutes=0.1, seed=1, threads=2)
    env.reset()
    assert stepping_threads() == before + 1
    del env
    gc.collect()
    assert stepping_threads() == before
    assert VectorEnv(2, opponent="idle", threads=8).threads == 2


def test_a_give_action_has_its_own_output_and_mask():
    # The shipped teams' settings and `give`: ten actions, the last one
    # `give`, allowed only where the robot has a teammate to give to.
    import naosoccer
    decision = dict(naosoccer.TEAM_DECISION, give=True)
    env = VectorEnv(2, decision=decision, obs_version=4, opponent="idle", minutes=0.1, seed=3)
    assert env.num_actions == 10 and env.action_names[-1] == "give"
    obs, infos = env.reset()
    mask = infos["action_mask"]
    assert mask.shape == (2, 4, 10)
    seen_give = False
    for _ in range(60):
        seen_give |= bool(mask[..., 9].any())
        # Give wherever it is allowed, else stay.
        actions = np.where(mask[..., 9], 9, 4)
        _, _, _, _, infos = env.step(actions)
        mask = infos["action_mask"]
    assert seen_give, "no robot ever had a teammate to give to"
    # A team without `give` has nine actions.
    assert VectorEnv(1, decision=naosoccer.TEAM_DECISION, obs_version=4, opponent="idle").num_actions == 9


def test_masks_follow_a_shipped_teams_actions():
    env = VectorEnv(2, like=TEAM, opponent="idle", minutes=0.1, seed=2)
    assert env.obs_version == 4 and env.num_actions == 9
    assert env.action_names == ("forward", "turn_left", "turn_right", "shoot", "stay", "pass", "support",
                                "approach", "defend")
    obs, infos = env.reset()
    assert obs.shape == (2, 4, 92)
    mask = infos["action_mask"]
    # At kick-off nobody has the ball in reach: no shoot, no pass; support
    # and stay always; the two robots farthest from the ball may not walk
    # or turn (the team's two chasers may).
    assert not mask[..., 3].any() and not mask[..., 5].any()
    assert mask[..., 4].all() and mask[..., 6].all()
    assert (mask[..., 0].sum(axis=1) == 2).all()
    rng = np.random.default_rng(1)
    for _ in range(30):
        # Random actions among the allowed ones.
        logits = np.where(mask, rng.random(mask.shape), -1.0)
        _, _, _, _, infos = env.step(logits.argmax(-1))
        mask = infos["action_mask"]
        assert mask.any(axis=-1).all()


def test_a_trained_opponent_plays():
    env = VectorEnv(2, opponent=f"ppo:{TEAM}", minutes=0.1, seed=4)
    env.reset()
    finals, _ = play_to_end(env, STAY)
    assert set(finals) == {0, 1}


def test_bad_arguments_are_refused():
    with pytest.raises(ValueError, match="team"):
        VectorEnv(1, team="green")
    with pytest.raises(ValueError, match="unknown policy"):
        VectorEnv(1, opponent="scripted-ish")
    with pytest.raises(ValueError, match="obs_version"):
        VectorEnv(1, obs_version=9)
    env = VectorEnv(2, opponent="idle", minutes=0.1)
    env.reset(seed=0)
    with pytest.raises(ValueError, match="not one of the 5 actions"):
        env.step(np.full((2, 4), 5))
    with pytest.raises(ValueError, match="expected 8 actions"):
        env.step(np.zeros(7, dtype=np.int64))


SCENARIO = "assets/scenarios/empty-goal-close.toml"


@pytest.mark.parametrize("team", ["blue", "red"])
def test_a_scenario_plays_as_the_cli_scenario_match(binary, team):
    # Every match starts from the scenario (its opponents the file's: idle)
    # and ends with its play, as `naosoccer match --scenario` plays it.
    env = VectorEnv(2, team=team, scenario=SCENARIO, seed=21)
    assert env.opponent == "idle"
    env.reset()
    finals = {}
    while len(finals) < 2:
        _, _, term, _, infos = env.step(np.full((2, 4), STAY))
        for i in np.flatnonzero(term):
            finals.setdefault(int(i), {
                "state_hash": infos["final_info"]["state_hash"][i],
                "seed": int(infos["final_info"]["seed"][i]),
                "ending": infos["final_info"]["scenario"]["ending"][i],
                "ticks": int(infos["final_info"]["scenario"]["ticks"][i]),
            })
    for i in range(2):
        out = subprocess.run(
            [binary, "match", "--scenario", SCENARIO, "--own", team, "--seed", str(21 + i),
             "--blue", "idle", "--red", "idle", "--json"],
            check=True, capture_output=True, text=True,
        )
        cli = json.loads(out.stdout)
        assert finals[i]["seed"] == 21 + i
        assert finals[i]["state_hash"] == cli["state_hash"], (team, i)
        assert finals[i]["ending"] == cli["scenario"]["ending"]
        assert finals[i]["ticks"] == cli["scenario"]["ticks"]



KEEPER = "assets/scenarios/1-vs-1-keeper.toml"
DRILLS = [SCENARIO, KEEPER]
NAMES = {SCENARIO: "empty-goal-close", KEEPER: "1-vs-1-keeper"}
SHOOT = 3


def drill_finals(env, count, seed=None):
    """(seed, scenario name, state hash) of the first ``count`` matches that
    end after ``reset(seed=seed)``, every robot shooting, in the order they
    end (slot order within a step)."""
    env.reset(seed=seed)
    finals = []
    while len(finals) < count:
        _, _, term, _, infos = env.step(np.full((env.num_envs, env.robots), SHOOT))
        for i in np.flatnonzero(term):
            final = infos["final_info"]
            assert {k for k in final["scenario"] if not k.startswith("_")} == {"name", "ending", "success", "ticks"}
            finals.append((int(final["seed"][i]), str(final["scenario"]["name"][i]), final["state_hash"][i]))
    return finals[:count]


def test_a_list_of_scenarios_draws_one_per_match():
    # The two drills name different built-in opponents (idle, scripted):
    # each match plays its own drill's.
    env = VectorEnv(4, scenario=DRILLS, seed=5, threads=3)
    assert env.opponent == "per scenario"
    finals = drill_finals(env, 12)
    assert {name for _, name, _ in finals} == set(NAMES.values()), finals
    # The same seed, the same scenarios and matches, with any threads.
    assert drill_finals(VectorEnv(4, scenario=DRILLS, seed=5, threads=1), 12) == finals
    # Each match is its scenario's alone, opponents included; restarts too.
    for seed, name, state_hash in finals[:2] + finals[-2:]:
        path = next(p for p in DRILLS if NAMES[p] == name)
        alone = VectorEnv(1, scenario=path)
        assert drill_finals(alone, 1, seed=seed) == [(seed, name, state_hash)]


def test_the_draw_follows_the_weights():
    # Right after a reset each slot's match is at the start of the scenario
    # it drew, the start that scenario alone draws for the match's seed.
    def starts(**kwargs):
        env = VectorEnv(16, threads=1, **kwargs)
        env.reset(seed=40)
        return env.state_hashes()

    near, keeper = starts(scenario=SCENARIO), starts(scenario=KEEPER)
    assert all(a != b for a, b in zip(near, keeper))
    drawn = starts(scenario=DRILLS)
    assert all(h in (a, b) for h, a, b in zip(drawn, near, keeper))
    assert set(near) & set(drawn) and set(keeper) & set(drawn), "both drawn"
    assert starts(scenario=DRILLS, scenario_weights=[1, 3]) != drawn
    # A scenario of weight 0 is never drawn; a tuple is a list too.
    assert starts(scenario=DRILLS, scenario_weights=[0, 2.5]) == keeper
    assert starts(scenario=tuple(DRILLS), scenario_weights=(1, 0)) == near


def test_a_list_of_one_is_the_scenario_alone():
    def trace(scenario, **kwargs):
        env = VectorEnv(2, scenario=scenario, seed=21, threads=1, **kwargs)
        assert env.opponent == "idle"
        env.reset()
        hashes = [env.state_hashes()]
        for _ in range(200):                                   # the first matches end, then more
            _, _, term, _, infos = env.step(np.full((2, 4), SHOOT))
            hashes.append((env.state_hashes(), list(infos.get("final_info", {}).get("state_hash", []))))
        return hashes

    alone = trace(SCENARIO)
    assert trace([SCENARIO]) == alone
    assert trace([SCENARIO], scenario_weights=[4]) == alone
    assert trace(SCENARIO, scenario_weights=[1.0]) == alone


def test_list_opponents():
    # Files that name the same opponent: that one; an opponent given: it.
    assert VectorEnv(1, scenario=[SCENARIO, SCENARIO]).opponent == "idle"
    assert VectorEnv(1, scenario=DRILLS, opponent="random").opponent == "random"
    assert VectorEnv(1, team="both", scenario=DRILLS).opponent is None
    # A trained team among different opponents needs `opponent=`.
    trained = open(KEEPER).read().replace('opponent = "scripted"', f'opponent = "ppo:{TEAM}"')
    with pytest.raises(ValueError, match=r"scenario\[1\] \(1-vs-1-keeper\).*pass opponent="):
        VectorEnv(1, scenario=[SCENARIO, trained])
    env = VectorEnv(1, scenario=[SCENARIO, trained], opponent=f"ppo:{TEAM}")
    assert env.opponent == f"ppo:{TEAM}"
    # All naming the same trained team: it plays every match.
    assert VectorEnv(1, scenario=[trained, trained]).opponent == f"ppo:{TEAM}"


@pytest.mark.parametrize("weights", [[1], [1, 2, 3], [1, -1], [float("nan"), 1], [float("inf"), 1],
                                     [0, 0], ["a", 1], "11", 2])
def test_bad_weights_raise(weights):
    with pytest.raises(ValueError, match="^scenario_weights: "):
        VectorEnv(1, scenario=DRILLS, scenario_weights=weights)


def test_bad_lists_raise():
    with pytest.raises(ValueError, match="^scenario: an empty list"):
        VectorEnv(1, scenario=[])
    with pytest.raises(ValueError, match="^scenario_weights: given without a scenario"):
        VectorEnv(1, scenario_weights=[1])
    far = 'name = "far"\n[ball]\nx = 4.0\ny = 0\n'
    with pytest.raises(ValueError, match=r"^scenario\[1\] \(far\): .*`ball.x`"):
        VectorEnv(1, scenario=[SCENARIO, far])
    with pytest.raises(ValueError, match=r"^scenario\[0\]: invalid scenario"):
        VectorEnv(1, scenario=["name = 3\n", SCENARIO])
    with pytest.raises(FileNotFoundError):
        VectorEnv(1, scenario=[SCENARIO, "no-such-file.toml"])
