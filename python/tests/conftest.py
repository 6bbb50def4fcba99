"""Fixtures that start a real ``naosoccer server`` through the package's
launcher (free loopback port, readiness from its printed address and tokens)."""

import pytest

from naosoccer import LocalServer, find_binary


@pytest.fixture(scope="session")
def binary():
    try:
        return find_binary()
    except Exception as e:  # pragma: no cover - reported as a failure, not a skip
        pytest.fail(f"the naosoccer binary is needed for these tests: {e}")


@pytest.fixture
def server(binary):
    with LocalServer(binary) as s:
        yield s
