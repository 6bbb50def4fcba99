"""A blocking socket client for the naosoccer server (docs/PROTOCOL.md).

Requests get exactly one reply each, in order (a result or an ``error``);
after a join the server also pushes one ``observation`` per tick, one
``match_end``, and an ``error`` with ``in_reply_to: "action"`` for each
rejected action. :meth:`Client.request` keeps pushes that arrive before its
reply, and :meth:`Client.recv` returns them first, in order.
"""

from __future__ import annotations

import os
import socket
from collections import deque
from typing import Any, Deque, Dict, Iterable, List, Optional, Sequence, Tuple, Union

from . import protocol
from .errors import NaoSoccerError, ProtocolError

_RECV_CHUNK = 256 * 1024
#: Cap on frames from the server. ``welcome.max_frame`` bounds what the server
#: accepts, not what it sends (a long match list can be larger than one team
#: observation), so this is a separate, generous bound against a broken peer.
RECV_MAX_FRAME = 16 * 1024 * 1024


class Client:
    """One connection: connect, handshake, then requests and match traffic.

    >>> c = Client("127.0.0.1", 7878)            # doctest: +SKIP
    >>> joined = c.join("blue", token, [0, 1, 2, 3], match_id=1)
    >>> msg = c.recv()                           # an observation
    >>> c.send_actions(msg["tick"], [(p, "forward") for p in range(4)])
    """

    def __init__(
        self,
        host: str = "127.0.0.1",
        port: int = 7878,
        *,
        timeout: Optional[float] = 60.0,
        client_name: str = "naosoccer-python",
    ) -> None:
        try:
            self._sock = socket.create_connection((host, port), timeout=timeout)
        except OSError as e:
            raise ProtocolError(f"cannot connect to {host}:{port}: {e}") from e
        self._sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        self._decoder = protocol.FrameDecoder(RECV_MAX_FRAME)
        self._closed = False
        self._pending: Deque[Dict[str, Any]] = deque()
        self.host, self.port = host, port
        #: The largest payload the server accepts; larger requests are refused here.
        self.max_frame = protocol.DEFAULT_MAX_FRAME
        try:
            self.welcome = self.request(protocol.hello(client_name), expect="welcome")
        except BaseException:
            self.close()
            raise
        self.max_frame = int(self.welcome.get("max_frame", protocol.DEFAULT_MAX_FRAME))

    # ------------------------------------------------------------ raw frames

    def send(self, msg: Dict[str, Any]) -> None:
        frame = protocol.encode_frame(msg)
        if len(frame) - protocol.HEADER_LEN > self.max_frame:
            raise ValueError(
                f"a {msg.get('type')!r} message of {len(frame) - protocol.HEADER_LEN} bytes "
                f"exceeds the server's {self.max_frame}-byte frame cap"
            )
        self._send_bytes(frame)

    def _send_bytes(self, data: bytes) -> None:
        if self._closed:
            raise ProtocolError("the connection is closed")
        try:
            self._sock.sendall(data)
        except OSError as e:
            self.close()
            raise ProtocolError(f"sending to the server failed: {e}") from e

    def recv_raw(self) -> Dict[str, Any]:
        """The next message, whatever it is (errors are returned, not raised)."""
        while True:
            try:
                payload = self._decoder.next_frame()
            except ValueError as e:
                self.close()
                raise ProtocolError(f"bad frame from the server: {e}") from e
            if payload is not None:
                try:
                    return protocol.decode_message(payload)
                except ValueError as e:
                    raise ProtocolError(f"bad message from the server: {e}") from e
            if self._closed:
                raise ProtocolError("the connection is closed")
            try:
                data = self._sock.recv(_RECV_CHUNK)
            except socket.timeout as e:
                raise ProtocolError("timed out waiting for the server") from e
            except OSError as e:
                self.close()
                raise ProtocolError(f"receiving from the server failed: {e}") from e
            if not data:
                self.close()
                raise ProtocolError("the server closed the connection")
            self._decoder.feed(data)

    def recv(self) -> Dict[str, Any]:
        """The next message; an ``error`` is raised as :class:`NaoSoccerError`.

        Pushes (observations, ``match_end``, action rejections) that arrived
        while :meth:`request` waited for its reply come first, in order.
        Messages of types this client does not know (from a newer minor
        protocol version) are skipped.
        """
        while True:
            msg = self._pending.popleft() if self._pending else self.recv_raw()
            kind = msg["type"]
            if kind == "error":
                err = NaoSoccerError.from_msg(msg)
                if err.fatal:
                    self.close()
                raise err
            if kind in _KNOWN_SERVER_TYPES:
                return msg

    # ------------------------------------------------------------ requests

    def request(self, msg: Dict[str, Any], expect: Optional[str] = None) -> Dict[str, Any]:
        """Sends a request and returns its reply (an ``error`` reply is raised).

        Pushes that arrive before the reply are kept for :meth:`recv`, so a
        request in the middle of a match loses no observation.
        """
        self.send(msg)
        while True:
            reply = self.recv_raw()
            kind = reply["type"]
            if _is_push(reply):
                self._pending.append(reply)
                continue
            if kind == "error":
                err = NaoSoccerError.from_msg(reply)
                if err.fatal:
                    self.close()
                raise err
            if kind not in _KNOWN_SERVER_TYPES:
                continue
            if expect is not None and kind != expect:
                raise ProtocolError(f"expected {expect!r} from the server, got {kind!r}")
            return reply

    def ping(self, nonce: int = 0) -> int:
        return int(self.request({"type": "ping", "nonce": nonce}, expect="pong")["nonce"])

    def create_match(
        self,
        token: str,
        *,
        seed: Optional[int] = None,
        minutes: Optional[float] = None,
        mode: Optional[str] = None,
        fill: Optional[str] = None,
        start_players: Optional[int] = None,
        deadline_ms: Optional[int] = None,
        scenario: Optional[Union[str, "os.PathLike[str]"]] = None,
        scenario_team: Optional[str] = None,
    ) -> Dict[str, Any]:
        """Creates a match (admin token); returns its ``MatchInfo``.

        ``scenario`` (protocol 1.5) starts it from a scenario: a path or the
        file's TOML text (see :func:`naosoccer.protocol.scenario_text`);
        ``scenario_team`` is the colour its own team plays (the server's
        default: blue)."""
        msg: Dict[str, Any] = {"type": "create_match", "token": token}
        text = protocol.scenario_text(scenario) if scenario is not None else None
        for key, value in (
            ("seed", seed),
            ("minutes", minutes),
            ("mode", mode),
            ("fill", fill),
            ("start_players", start_players),
            ("deadline_ms", deadline_ms),
            ("scenario", text),
            ("scenario_team", scenario_team),
        ):
            if value is not None:
                msg[key] = value
        return self.request(msg, expect="match_created")["info"]

    def end_match(self, token: str, match_id: int) -> Dict[str, Any]:
        """Ends a match early (admin token; protocol 1.2); returns its final
        ``MatchInfo``. Every client of the match gets a ``match_end`` with
        reason ``ended`` first."""
        msg = {"type": "end_match", "token": token, "match_id": int(match_id)}
        return self.request(msg, expect="match_ended")["info"]

    def set_state(
        self,
        token: str,
        match_id: int,
        *,
        ball: Optional[Dict[str, float]] = None,
        robots: Optional[Sequence[Dict[str, Any]]] = None,
    ) -> int:
        """Moves the ball and robots of a match before its next tick (admin
        token; protocol 1.5), world coordinates: ``ball`` as
        ``{"x", "y", "vx", "vy"}``, ``robots`` as ``{"robot", "x", "y",
        "heading", "fallen"}`` (docs/PROTOCOL.md, ``set_state``). Returns the
        tick that is then played from the new state."""
        msg: Dict[str, Any] = {"type": "set_state", "token": token, "match_id": int(match_id)}
        if ball is not None:
            msg["ball"] = dict(ball)
        if robots:
            msg["robots"] = [dict(r) for r in robots]
        return int(self.request(msg, expect="state_set")["tick"])

    def list_matches(self) -> List[Dict[str, Any]]:
        return self.request({"type": "list_matches"}, expect="match_list")["matches"]

    def join(
        self,
        team: str,
        token: str,
        players: Iterable[int] = range(protocol.PLAYERS_PER_TEAM),
        match_id: Optional[int] = None,
    ) -> Dict[str, Any]:
        """Takes control of ``players`` of ``team``; returns the ``joined`` reply.

        Without ``match_id`` the server picks the oldest unfinished match
        where those slots are free. Observations follow once the match starts.
        """
        msg: Dict[str, Any] = {"type": "join", "team": team, "token": token, "players": list(players)}
        if match_id is not None:
            msg["match_id"] = int(match_id)
        return self.request(msg, expect="joined")

    def leave(self) -> None:
        """Leaves the current match, discarding its pending traffic.

        Leaving a match that has just ended is not an error: the server then
        answers ``failed_precondition`` (not in a match), which is swallowed.
        """
        # Whatever the match pushed before the server saw the leave is moot.
        self._pending.clear()
        self.send({"type": "leave"})
        while True:
            reply = self.recv_raw()
            kind = reply["type"]
            if _is_push(reply) or kind not in _KNOWN_SERVER_TYPES | {"error"}:
                continue
            if kind == "left":
                return
            if kind == "error":
                err = NaoSoccerError.from_msg(reply)
                if err.code == "failed_precondition" and err.in_reply_to == "leave":
                    return
                if err.fatal:
                    self.close()
                raise err
            raise ProtocolError(f"expected 'left' from the server, got {kind!r}")

    # ------------------------------------------------------------ match traffic

    def send_actions(
        self,
        tick: int,
        actions: Sequence[Tuple[int, Any]],
        team: Optional[str] = None,
    ) -> None:
        """Answers the observation of ``tick`` with ``(player, action)`` pairs.

        Actions are indices 0..5 (see :data:`protocol.ALL_ACTIONS`) or names. No
        reply follows unless the server rejects them; the rejection then
        arrives as the next message and :meth:`recv` raises it.
        """
        self.send(protocol.action_msg(tick, list(actions), team))

    def close(self) -> None:
        if not self._closed:
            self._closed = True
            try:
                self._sock.close()
            except OSError:
                pass

    @property
    def closed(self) -> bool:
        return self._closed

    def __enter__(self) -> "Client":
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()


def _is_push(msg: Dict[str, Any]) -> bool:
    """Match traffic, as opposed to the reply to a request (PROTOCOL.md section 2)."""
    kind = msg["type"]
    return kind in protocol.PUSHED_TYPES or (kind == "error" and msg.get("in_reply_to") == "action")


_KNOWN_SERVER_TYPES = frozenset(
    {
        "welcome",
        "match_created",
        "match_list",
        "joined",
        "observation",
        "match_end",
        "left",
        "pong",
        "match_ended",
        "state_set",
    }
)
