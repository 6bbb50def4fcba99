"""The low-level client against a real server."""

import pytest

from naosoccer import Client, NaoSoccerError, protocol


def test_handshake_ping_and_lobby(server):
    with Client(server.host, server.port) as c:
        assert c.welcome["protocol"] == "naosoccer"
        assert c.welcome["version"]["major"] == protocol.PROTOCOL_VERSION[0]
        assert c.ping(41) == 41
        assert c.list_matches() == []
        info = c.create_match(server.tokens["admin"], seed=9, minutes=0.1, fill="idle", start_players=4)
        assert info["seed"] == 9 and info["state"] == "waiting"
        assert [m["match_id"] for m in c.list_matches()] == [info["match_id"]]


def test_errors_carry_the_server_code(server):
    with Client(server.host, server.port) as c:
        with pytest.raises(NaoSoccerError) as e:
            c.create_match("not-the-admin-token")
        assert e.value.code == "permission_denied" and e.value.in_reply_to == "create_match"
        assert not e.value.fatal
        with pytest.raises(NaoSoccerError) as e:
            c.join("blue", server.tokens["blue"], [0], match_id=999)
        assert e.value.code == "not_found"
        with pytest.raises(NaoSoccerError) as e:
            c.join("red", server.tokens["blue"], [0])
        assert e.value.code == "permission_denied"
        # The connection survives non-fatal errors.
        assert c.ping(1) == 1


def test_robot_client_plays_and_rejected_actions_raise(server):
    with Client(server.host, server.port) as c:
        info = c.create_match(server.tokens["admin"], seed=2, minutes=0.05, fill="scripted", start_players=1)
        joined = c.join("red", server.tokens["red"], [2], match_id=info["match_id"])
        assert joined["team"] == "red" and joined["players"] == [2]
        msg = c.recv()
        assert msg["type"] == "observation" and msg["tick"] == 0
        (obs,) = msg["observations"]
        assert obs["team"] == "red" and obs["player"] == 2
        # Acting for a robot this connection does not control.
        c.send_actions(msg["tick"], [(0, "forward")])
        with pytest.raises(NaoSoccerError) as e:
            c.recv()
        assert e.value.code == "permission_denied" and e.value.in_reply_to == "action"
        assert e.value.tick == 0
        c.send_actions(msg["tick"], [(2, "forward")])
        ticks = 1
        while True:
            msg = c.recv()
            if msg["type"] == "match_end":
                break
            assert msg["tick"] == ticks
            ticks += 1
            c.send_actions(msg["tick"], [(2, "turn_left")])
        assert msg["reason"] == "finished" and msg["tick"] == ticks
        assert msg["misses"]["red"] == [0, 0, 0, 0]


def test_major_version_mismatch_is_fatal(server):
    import socket

    with socket.create_connection((server.host, server.port), timeout=30) as s:
        s.sendall(protocol.encode_frame({"type": "hello", "protocol": "naosoccer", "version": {"major": 99, "minor": 0}}))
        dec = protocol.FrameDecoder()
        while (frame := dec.next_frame()) is None:
            data = s.recv(65536)
            assert data, "closed before an answer"
            dec.feed(data)
        msg = protocol.decode_message(frame)
        assert msg["type"] == "error" and msg["code"] == "unimplemented" and msg["fatal"] is True


def test_requests_during_a_match_keep_the_pushes(server):
    with Client(server.host, server.port) as c:
        info = c.create_match(server.tokens["admin"], seed=5, minutes=0.05, fill="idle", start_players=1)
        c.join("blue", server.tokens["blue"], [1], match_id=info["match_id"])
        msg = c.recv()
        assert msg["tick"] == 0
        c.send_actions(0, [(3, "forward")])  # rejected: player 3 is not ours
        c.send_actions(0, [(1, "forward")])
        # The rejection and tick 1's observation arrive while the ping waits.
        assert c.ping(7) == 7
        assert [m["match_id"] for m in c.list_matches()] == [info["match_id"]]
        with pytest.raises(NaoSoccerError) as e:
            c.recv()
        assert e.value.code == "permission_denied" and e.value.tick == 0
        msg = c.recv()
        assert msg["type"] == "observation" and msg["tick"] == 1
        c.leave()
        # Back in the lobby: leaving again is an error the server names.
        with pytest.raises(NaoSoccerError) as e:
            c.request({"type": "leave"})
        assert e.value.code == "failed_precondition"


def test_end_match_sends_match_end_to_every_client(server):
    # Protocol 1.2: an admin ends a match early; each of its clients gets a
    # match_end with reason "ended", the admin the final MatchInfo.
    with Client(server.host, server.port) as admin, Client(server.host, server.port) as blue, Client(
        server.host, server.port
    ) as red:
        info = admin.create_match(server.tokens["admin"], seed=3, minutes=1, fill="idle", start_players=2)
        mid = info["match_id"]
        blue.join("blue", server.tokens["blue"], [0], match_id=mid)
        red.join("red", server.tokens["red"], [3], match_id=mid)
        for tick in range(3):
            for c, p in ((blue, 0), (red, 3)):
                msg = c.recv()
                assert msg["type"] == "observation" and msg["tick"] == tick
                if tick < 2:
                    c.send_actions(tick, [(p, "stay")])
        with pytest.raises(NaoSoccerError) as e:
            admin.end_match(server.tokens["blue"], mid)
        assert e.value.code == "permission_denied" and e.value.in_reply_to == "end_match"
        ended = admin.end_match(server.tokens["admin"], mid)
        assert ended["state"] == "finished" and ended["tick"] == 2
        for c in (blue, red):
            end = c.recv()
            assert end["type"] == "match_end" and end["reason"] == "ended" and end["tick"] == 2
        with pytest.raises(NaoSoccerError) as e:
            admin.end_match(server.tokens["admin"], mid)
        assert e.value.code == "failed_precondition"


def test_env_truncates_an_ended_match(binary):
    from naosoccer import LocalServer, NaoSoccerParallelEnv

    with LocalServer(binary) as srv:
        env = NaoSoccerParallelEnv(
            host=srv.host, port=srv.port, token=srv.tokens["blue"], admin_token=srv.tokens["admin"], minutes=1
        )
        try:
            env.reset(seed=1)
            env.step({a: 4 for a in env.agents})
            with Client(srv.host, srv.port) as admin:
                admin.end_match(srv.tokens["admin"], env.match_id)
            _, _, terms, truncs, infos = env.step({a: 4 for a in env.agents})
            assert env.agents == []
            assert all(truncs.values()) and not any(terms.values())
            assert infos["blue_0"]["match_end"]["reason"] == "ended"
        finally:
            env.close()


SCENARIO = """name = "still"
[ball]
x = 1.0
y = 0.5

[[robot]]
side = "own"
player = 2
x = -1.0
y = 0.0
"""


def test_scenario_and_set_state(server, tmp_path):
    admin = server.tokens["admin"]
    with Client(server.host, server.port) as c:
        # Protocol 1.5: a match from a scenario, given as a path or as text.
        path = tmp_path / "still.toml"
        path.write_text(SCENARIO)
        info = c.create_match(admin, seed=3, fill="idle", start_players=1, scenario=path, scenario_team="red")
        assert info["scenario"] == {"name": "still", "team": "red"}
        with pytest.raises(NaoSoccerError) as e:
            c.create_match(admin, scenario=SCENARIO.replace("player = 2", "player = 5"))
        assert e.value.code == "invalid_argument" and "`robot[0].player`" in e.value.message
        # The state set before the start is the first observation.
        tick = c.set_state(
            admin,
            info["match_id"],
            ball={"x": -2.0, "y": 1.0},
            robots=[{"robot": 6, "x": 1.5, "y": -0.5, "heading": 0.0}],
        )
        assert tick == 0
        with pytest.raises(NaoSoccerError) as e:
            c.set_state(admin, info["match_id"], robots=[{"robot": 0, "x": 0.0, "y": 0.0}])
        assert e.value.code == "invalid_argument" and "out of play" in e.value.message
        c.join("red", server.tokens["red"], [2], match_id=info["match_id"])
        msg = c.recv()
        (obs,) = msg["observations"]
        # Red's frame: the world turned half round.
        assert (obs["ball"]["x"], obs["ball"]["y"]) == (2.0, -1.0)
        assert (obs["own"][2]["x"], obs["own"][2]["y"]) == (-1.5, 0.5)
        c.send_actions(msg["tick"], [(2, "stay")])
        msg = c.recv()
        assert [e["kind"] for e in msg["events"]] == ["state_set"]
