"""Framing, message helpers and the observation vector, without a server."""

import json
import math
import struct

import numpy as np
import pytest

from naosoccer import protocol
from naosoccer.errors import NaoSoccerError
from naosoccer.obs import (
    FEATURE_NAMES,
    OBS_DIM,
    OBS_HIGH,
    OBS_LOW,
    FieldScale,
    ObservationEncoder,
    RewardWeights,
    log_compress,
    team_rewards,
)


def test_ping_frame_bytes_match_the_rust_encoder():
    # The same bytes crates/proto/src/frame.rs's `ping_frame_bytes` expects.
    assert protocol.encode_frame({"type": "ping"}) == b"\x00\x00\x00\x0f" + b'{"type":"ping"}'


def test_decoder_waits_for_complete_frames():
    a = protocol.encode_frame({"type": "pong", "nonce": 1})
    b = protocol.encode_frame({"type": "pong", "nonce": 2, "text": "é"})
    stream = a + b
    dec = protocol.FrameDecoder()
    got = []
    for i in range(len(stream)):
        dec.feed(stream[i : i + 1])
        frame = dec.next_frame()
        if frame is not None:
            got.append(protocol.decode_message(frame))
            assert dec.next_frame() is None
    assert got == [{"type": "pong", "nonce": 1}, {"type": "pong", "nonce": 2, "text": "é"}]
    assert dec.buffered() == 0


def test_decoder_checks_cap_from_header_alone():
    dec = protocol.FrameDecoder(max_frame=1024)
    dec.feed(struct.pack(">I", 1025))
    with pytest.raises(protocol.FrameTooLarge):
        dec.next_frame()
    dec = protocol.FrameDecoder(max_frame=1024)
    dec.feed(struct.pack(">I", 0))
    with pytest.raises(ValueError):
        dec.next_frame()
    dec = protocol.FrameDecoder(max_frame=1024)
    dec.feed(struct.pack(">I", 1024))
    assert dec.next_frame() is None


def test_messages_need_a_type():
    with pytest.raises(ValueError):
        protocol.decode_message(b"[1, 2]")
    with pytest.raises(ValueError):
        protocol.decode_message(b'{"kind": "ping"}')


def test_action_message_uses_wire_names_and_passes_bad_values_through():
    msg = protocol.action_msg(7, [(0, 0), (1, "shoot"), (2, np.int64(4)), (3, 9)])
    assert msg == {
        "type": "action",
        "tick": 7,
        "actions": [
            {"player": 0, "action": "forward"},
            {"player": 1, "action": "shoot"},
            {"player": 2, "action": "stay"},
            {"player": 3, "action": 9},
        ],
    }
    json.dumps(msg)  # numpy integers were converted
    assert protocol.ACTIONS == ("forward", "turn_left", "turn_right", "shoot", "stay")
    # Protocol 1.3's sixth action, by index or name.
    msg = protocol.action_msg(8, [(0, 5), (1, "pass")])
    assert [a["action"] for a in msg["actions"]] == ["pass", "pass"]
    assert protocol.ALL_ACTIONS[:5] == protocol.ACTIONS and protocol.ACTION_INDEX["pass"] == 5


def test_hello_names_the_protocol_and_version():
    h = protocol.hello("t")
    assert h["type"] == "hello" and h["protocol"] == "naosoccer"
    assert h["version"] == {"major": 1, "minor": 6}


def test_error_carries_the_server_fields():
    e = NaoSoccerError.from_msg(
        {"type": "error", "code": "permission_denied", "message": "no", "fatal": False, "in_reply_to": "action", "tick": 3}
    )
    assert (e.code, e.message, e.fatal, e.in_reply_to, e.tick) == ("permission_denied", "no", False, "action", 3)
    assert "permission_denied: no" in str(e) and "tick 3" in str(e)


def robot(x, y, heading, fallen=False):
    return {"x": x, "y": y, "heading": heading, "fallen": fallen}


def team_obs(player, **over):
    o = {
        "tick": 5,
        "team": "blue",
        "player": player,
        "time_left": 30.0,
        "score": {"own": 2, "opponent": 1},
        "own": [robot(-2.6, 0.0, 0.0), robot(-0.3, 0.0, 0.0), robot(-1.0, 1.2, math.pi / 2, True), robot(-1.2, -1.0, 0.0)],
        "opponents": [robot(2.6, 0.0, math.pi), robot(1.0, 0.0, math.pi), robot(1.5, -1.2, math.pi), robot(1.8, 1.0, math.pi)],
        "ball": {"x": 0.0, "y": 0.0, "vx": 1.0, "vy": -0.5},
        "control": [False, True, False, False],
        "opponent_control": False,
    }
    o.update(over)
    return o


def test_encoder_layout():
    enc = ObservationEncoder(FieldScale(6.0, 4.5), match_seconds=60.0)
    vecs = enc.encode_team([team_obs(p) for p in range(4)])
    assert len(vecs) == 4
    names = {n: i for i, n in enumerate(FEATURE_NAMES)}
    for p, v in enumerate(vecs):
        assert v.shape == (OBS_DIM,) and v.dtype == np.float32
        assert np.all(v >= OBS_LOW) and np.all(v <= OBS_HIGH)
        assert [v[names[f"me{q}"]] for q in range(4)] == [1.0 if q == p else 0.0 for q in range(4)]
    v = vecs[1]
    assert v[names["own0_x"]] == pytest.approx(-2.6 / 3.0)
    assert v[names["own2_y"]] == pytest.approx(1.2 / 2.25)
    assert v[names["own2_sin"]] == pytest.approx(1.0)
    assert v[names["own2_fallen"]] == 1.0 and v[names["own1_fallen"]] == 0.0
    assert v[names["ball_vx"]] == pytest.approx(0.5)
    assert v[names["control1"]] == 1.0 and v[names["opponent_control"]] == 0.0
    assert v[names["opp3_x"]] == pytest.approx(1.8 / 3.0)
    assert v[names["opp0_cos"]] == pytest.approx(-1.0)
    assert v[names["time_left"]] == pytest.approx(0.5)
    assert v[names["score_own"]] == pytest.approx(0.2) and v[names["score_opponent"]] == pytest.approx(0.1)
    # Player 1 stands 0.3 m behind the ball, facing it.
    assert v[names["ball_fwd"]] == pytest.approx(0.3 / 3.0) and v[names["ball_left"]] == pytest.approx(0.0, abs=1e-6)
    # Player 2 faces +y: the ball (1 m ahead in x, 1.2 m to the right) is to its right.
    assert vecs[2][names["ball_left"]] < 0


def test_docs_list_the_same_layout():
    import pathlib

    doc = pathlib.Path(__file__).resolve().parents[2] / "docs" / "PYTHON.md"
    text = doc.read_text()
    # The layout's rows: an index, then a feature name in backticks (other
    # tables of the page, such as the speed table, start with numbers too).
    rows = [
        line.split("|")[2].strip().strip("`")
        for line in text.splitlines()
        if line.startswith("| ") and line.split("|")[1].strip().isdigit() and line.split("|")[2].strip().startswith("`")
    ]
    assert tuple(rows) == FEATURE_NAMES


def test_reward_terms():
    w = RewardWeights()
    after = team_obs(0)
    r = team_rewards(w, after, 0, 0)
    d1 = 0.3
    assert r[1] == pytest.approx(log_compress(w.close * math.exp(-d1) + w.control))
    assert r[0] == pytest.approx(log_compress(w.close * math.exp(-2.6)))
    r_goal = team_rewards(w, after, 1, 0)
    assert all(g > x for g, x in zip(r_goal, r))
    assert team_rewards(w, None, 0, 1) == [log_compress(-w.goal)] * 4
    opp = team_rewards(w, team_obs(0, control=[False] * 4, opponent_control=True), 0, 0)
    assert opp[0] < 0
    assert log_compress(0.0) == 0.0 and log_compress(-1.0) == pytest.approx(-math.log(2.0))
