"""Record mode ``none`` blocks every connection but loopback."""

from __future__ import annotations

import socket

import pytest

from pytest_emrd.cassette import network_blocked
from pytest_emrd.errors import CassetteError


def test_remote_addresses_are_refused_and_loopback_is_not(server):
    with (
        network_blocked(),
        socket.socket() as sock,
        pytest.raises(CassetteError, match="network is blocked"),
    ):
        sock.connect(("192.0.2.1", 443))
    host, port = server.url.removeprefix("http://").split(":")
    with network_blocked(), socket.create_connection((host, int(port)), timeout=2):
        pass
