"""Starting a local ``naosoccer server`` as a subprocess.

The server binds a free loopback port (``--port 0``) and prints its address
and tokens on stdout; :class:`LocalServer` waits for those lines (with a
bounded timeout, never a fixed sleep) and stops the process with SIGTERM.
"""

from __future__ import annotations

import os
import queue
import re
import shutil
import subprocess
import tempfile
import threading
import time
import weakref
from pathlib import Path
from typing import IO, Dict, List, Optional, Sequence

from .errors import ServerStartError

#: Environment variable naming the ``naosoccer`` binary.
BIN_ENV = "NAOSOCCER_BIN"

_ADDR_RE = re.compile(r"^naosoccer server on (\S+):(\d+)\b")
_TOKEN_RE = re.compile(r"^(blue|red|admin) token:\s*(\S+)\s*$")


#: Where a wheel carries its ``naosoccer`` binary (scripts/wheel puts it there).
_BUNDLED = Path(__file__).resolve().parent / "bin" / "naosoccer"


def binary_path() -> Optional[str]:
    """The ``naosoccer`` binary this package carries, or ``None`` when it
    carries none (a checkout used in place, before scripts/wheel)."""
    if _BUNDLED.is_file() and os.access(_BUNDLED, os.X_OK):
        return str(_BUNDLED)
    return None


def find_binary(explicit: Optional[str] = None) -> str:
    """The ``naosoccer`` binary to run.

    In order: ``explicit``; ``$NAOSOCCER_BIN``; the package's own
    (:func:`binary_path`, in an installed wheel); the newer of
    ``target/release/naosoccer`` and ``target/debug/naosoccer`` in the
    repository this package lives in (or in the current directory or one of
    its parents); ``naosoccer`` on ``PATH``.
    """
    for candidate in (explicit, os.environ.get(BIN_ENV)):
        if candidate:
            if not (os.path.isfile(candidate) and os.access(candidate, os.X_OK)):
                raise ServerStartError(f"naosoccer binary {candidate!r} does not exist or is not executable")
            return candidate
    bundled = binary_path()
    if bundled:
        return bundled
    roots: List[Path] = [Path(__file__).resolve().parent.parent.parent]
    cwd = Path.cwd().resolve()
    roots += [cwd, *cwd.parents]
    for root in roots:
        found = [root / "target" / kind / "naosoccer" for kind in ("release", "debug")]
        found = [p for p in found if p.is_file() and os.access(p, os.X_OK)]
        if found:
            # A stale release build next to a fresh debug build would run old
            # code; the newest build is the one the developer just made.
            return str(max(found, key=lambda p: p.stat().st_mtime))
    on_path = shutil.which("naosoccer")
    if on_path:
        return on_path
    raise ServerStartError(
        "cannot find the naosoccer binary: build it (`cargo build --release`), "
        f"or set {BIN_ENV}, or pass binary=..."
    )


class LocalServer:
    """A ``naosoccer server`` child process on a free loopback port.

    ``args`` are extra command-line options (e.g. ``["--minutes", "1"]``).
    By default no match is created at start (``--matches 0``): clients create
    their own with the admin token. Matches are recorded to ``record_dir``
    when it is given (MCAP, one file per match), else not at all. Use as a context manager or call
    :meth:`stop`; the process is also stopped when the object is collected or
    the interpreter exits.
    """

    def __init__(
        self,
        binary: Optional[str] = None,
        args: Sequence[str] = (),
        *,
        matches: int = 0,
        startup_timeout: float = 60.0,
        record_dir: Optional[str] = None,
    ) -> None:
        self.binary = find_binary(binary)
        record = ["--record-dir", str(record_dir)] if record_dir else ["--no-record"]
        cmd = [self.binary, "server", "--bind", "127.0.0.1", "--port", "0", "--matches", str(matches), *record, *args]
        # The server logs to stderr; a file keeps a chatty server from
        # filling a pipe nobody reads, and keeps the log for error messages.
        self._log: IO[bytes] = tempfile.TemporaryFile(prefix="naosoccer-server-", suffix=".log")
        try:
            self.proc = subprocess.Popen(
                cmd,
                stdin=subprocess.DEVNULL,
                stdout=subprocess.PIPE,
                stderr=self._log,
                text=True,
                bufsize=1,
            )
        except OSError as e:
            self._log.close()
            raise ServerStartError(f"cannot run {self.binary}: {e}") from e
        self._finalizer = weakref.finalize(self, _stop_process, self.proc, self._log)
        self.host = ""
        self.port = 0
        self.tokens: Dict[str, str] = {}
        lines: "queue.Queue[Optional[str]]" = queue.Queue()
        threading.Thread(target=_pump, args=(self.proc.stdout, lines), daemon=True).start()
        deadline = time.monotonic() + startup_timeout
        while not (self.port and len(self.tokens) == 3):
            left = deadline - time.monotonic()
            try:
                line = lines.get(timeout=max(left, 0.0)) if left > 0 else None
            except queue.Empty:
                line = None
            if line is None:
                tail = self.log_tail()
                self.stop()
                raise ServerStartError(
                    f"{' '.join(cmd)} did not announce its address and tokens "
                    f"within {startup_timeout:.0f} s:\n{tail}"
                )
            m = _ADDR_RE.match(line)
            if m:
                self.host, self.port = m.group(1), int(m.group(2))
                continue
            m = _TOKEN_RE.match(line)
            if m:
                self.tokens[m.group(1)] = m.group(2)

    def log_tail(self, limit: int = 4000) -> str:
        """The end of the server's stderr log."""
        try:
            self._log.flush()
            self._log.seek(0, os.SEEK_END)
            size = self._log.tell()
            self._log.seek(max(0, size - limit))
            return self._log.read().decode("utf-8", "replace")
        except (OSError, ValueError):
            return ""

    @property
    def running(self) -> bool:
        return self.proc.poll() is None

    def stop(self) -> None:
        """SIGTERM, then SIGKILL if the server has not exited in 10 s."""
        self._finalizer()

    def __enter__(self) -> "LocalServer":
        return self

    def __exit__(self, *exc: object) -> None:
        self.stop()


def _pump(stream: Optional[IO[str]], lines: "queue.Queue[Optional[str]]") -> None:
    # Reads stdout to its end so the server never blocks on a full pipe.
    if stream is None:
        lines.put(None)
        return
    for line in stream:
        lines.put(line.rstrip("\n"))
    lines.put(None)


def _stop_process(proc: subprocess.Popen, log: IO[bytes]) -> None:
    if proc.poll() is None:
        proc.terminate()
        try:
            proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()
    if proc.stdout is not None:
        proc.stdout.close()
    log.close()
