"""Wire format of the naosoccer protocol (docs/PROTOCOL.md), IO-free.

Every message is a frame: a 4-byte big-endian payload length, then that many
bytes of UTF-8 JSON holding one object with a ``type`` field. The functions
here encode and decode frames in memory so that the socket client and the
tests share one implementation.
"""

from __future__ import annotations

import json
import os
import struct
from typing import Any, Dict, List, Optional, Tuple, Union

PROTOCOL_NAME = "naosoccer"
#: The protocol version this package speaks. The server must agree on the
#: major version; a newer minor version only adds optional fields and types.
PROTOCOL_VERSION = (1, 6)

HEADER_LEN = 4
#: The server's default cap on a frame's payload; ``welcome`` announces the
#: real one, which the client then enforces on what it receives.
DEFAULT_MAX_FRAME = 64 * 1024

PLAYERS_PER_TEAM = 4
TEAMS = ("blue", "red")

#: The paper's five actions, in the order of their discrete index (the same
#: order as the Rust ``Action::ALL``).
ACTIONS = ("forward", "turn_left", "turn_right", "shoot", "stay")
#: Every action the server takes: the paper's five and, from protocol 1.3,
#: ``pass`` (index 5), a kick toward the teammate the protocol's pass rule
#: names (docs/PROTOCOL.md, "action").
ALL_ACTIONS = ACTIONS + ("pass",)
ACTION_INDEX = {name: i for i, name in enumerate(ALL_ACTIONS)}
STAY = ACTION_INDEX["stay"]

#: Messages the server pushes without a request once a join is accepted.
PUSHED_TYPES = frozenset({"observation", "match_end"})

_HEADER = struct.Struct(">I")


class FrameTooLarge(ValueError):
    """A frame's announced length exceeds the cap (checked before reading it)."""


def encode_frame(msg: Dict[str, Any]) -> bytes:
    """One frame carrying ``msg`` as compact JSON."""
    payload = json.dumps(msg, separators=(",", ":")).encode("utf-8")
    return _HEADER.pack(len(payload)) + payload


class FrameDecoder:
    """Splits a byte stream into frames.

    ``feed`` appends received bytes; ``next_frame`` returns the payload of the
    next complete frame or ``None``. The announced length is checked against
    the cap from the header alone, before anything is buffered for it.
    """

    def __init__(self, max_frame: int = DEFAULT_MAX_FRAME) -> None:
        self.max_frame = max_frame
        self._buf = bytearray()
        self._pos = 0

    def feed(self, data: bytes) -> None:
        if self._pos and self._pos == len(self._buf):
            # Everything consumed: start over instead of growing forever.
            self._buf.clear()
            self._pos = 0
        self._buf += data

    def buffered(self) -> int:
        return len(self._buf) - self._pos

    def next_frame(self) -> Optional[bytes]:
        avail = len(self._buf) - self._pos
        if avail < HEADER_LEN:
            return None
        (length,) = _HEADER.unpack_from(self._buf, self._pos)
        if length > self.max_frame:
            raise FrameTooLarge(f"frame of {length} bytes exceeds the {self.max_frame}-byte cap")
        if length == 0:
            raise ValueError("empty frame (length 0)")
        end = self._pos + HEADER_LEN + length
        if len(self._buf) < end:
            return None
        payload = bytes(self._buf[self._pos + HEADER_LEN : end])
        self._pos = end
        if self._pos > 1 << 20:
            # Drop consumed bytes now and then so the buffer stays small.
            del self._buf[: self._pos]
            self._pos = 0
        return payload


def decode_message(payload: bytes) -> Dict[str, Any]:
    """The JSON object in a frame's payload; it must have a string ``type``."""
    msg = json.loads(payload)
    if not isinstance(msg, dict) or not isinstance(msg.get("type"), str):
        raise ValueError(f"a frame without a message type: {payload[:80]!r}")
    return msg


def action_name(action: Any) -> Any:
    """The wire name of an action given as an index (0..4) or a name.

    Anything else is passed through unchanged, so that the server, which owns
    validation, rejects it with its own error code (see
    :class:`naosoccer.NaoSoccerError`).
    """
    if isinstance(action, str):
        return action
    try:
        i = int(action)
    except (TypeError, ValueError):
        return action
    if i != action:
        return action
    if 0 <= i < len(ALL_ACTIONS):
        return ALL_ACTIONS[i]
    return i


def hello(client: str) -> Dict[str, Any]:
    return {
        "type": "hello",
        "protocol": PROTOCOL_NAME,
        "version": {"major": PROTOCOL_VERSION[0], "minor": PROTOCOL_VERSION[1]},
        "client": client,
    }


def action_msg(tick: int, actions: List[Tuple[int, Any]], team: Optional[str] = None) -> Dict[str, Any]:
    msg: Dict[str, Any] = {
        "type": "action",
        "tick": tick,
        "actions": [{"player": p, "action": action_name(a)} for p, a in actions],
    }
    if team is not None:
        msg["team"] = team
    return msg


def scenario_text(scenario: Union[str, "os.PathLike[str]"]) -> str:
    """A scenario file's TOML text (docs/SCENARIOS.md), for ``create_match``'s
    ``scenario`` (protocol 1.5) and the in-process envs.

    ``scenario`` is a path (an ``os.PathLike``, or a string naming an
    existing file), read here, or the file's text itself: a string that
    names no file and holds a newline or ``=``. Any other string is taken for
    a path, and a missing file raises ``FileNotFoundError``.
    """
    if not isinstance(scenario, str) or os.path.isfile(scenario):
        with open(scenario, encoding="utf-8") as f:
            return f.read()
    if "\n" in scenario or "=" in scenario:
        return scenario
    raise FileNotFoundError(f"no scenario file {scenario!r} (and it is not a scenario's TOML text)")
