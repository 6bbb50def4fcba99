"""Exceptions of the naosoccer client."""

from __future__ import annotations

from typing import Any, Dict, Optional


class NaoSoccerError(Exception):
    """An ``error`` message from the server.

    ``code`` is the server's stable error code (``invalid_argument``,
    ``failed_precondition``, ``not_found``, ``permission_denied``,
    ``unimplemented``, ``resource_exhausted``, ``deadline_exceeded``,
    ``unavailable``, ``internal``); ``fatal`` means the server closed the
    connection after sending it; ``in_reply_to`` names the request it answers
    and ``tick`` the tick a rejected action named.
    """

    def __init__(
        self,
        code: str,
        message: str,
        fatal: bool = False,
        in_reply_to: Optional[str] = None,
        tick: Optional[int] = None,
    ) -> None:
        self.code = code
        self.message = message
        self.fatal = fatal
        self.in_reply_to = in_reply_to
        self.tick = tick
        text = f"{code}: {message}"
        if in_reply_to:
            text += f" (in reply to {in_reply_to}"
            text += f", tick {tick})" if tick is not None else ")"
        if fatal:
            text += " [fatal: the server closed the connection]"
        super().__init__(text)

    @classmethod
    def from_msg(cls, msg: Dict[str, Any]) -> "NaoSoccerError":
        return cls(
            code=str(msg.get("code", "unknown")),
            message=str(msg.get("message", "")),
            fatal=bool(msg.get("fatal", False)),
            in_reply_to=msg.get("in_reply_to"),
            tick=msg.get("tick"),
        )


class ProtocolError(Exception):
    """The byte stream or a reply broke the protocol, or the connection closed."""


class ServerStartError(RuntimeError):
    """A local ``naosoccer server`` could not be started."""
