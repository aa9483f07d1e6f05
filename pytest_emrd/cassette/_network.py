"""Blocking the network while replaying: only loopback connections may be opened."""

from __future__ import annotations

import ipaddress
import socket
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

from pytest_emrd.errors import CassetteError


def _is_loopback(sock: socket.socket, address: Any) -> bool:
    if sock.family not in (socket.AF_INET, socket.AF_INET6):
        return True
    host = str(address[0])
    if host == "localhost":
        return True
    try:
        return ipaddress.ip_address(host.split("%", 1)[0]).is_loopback
    except ValueError:
        return False


@contextmanager
def network_blocked(active: bool = True) -> Iterator[None]:
    """While active, a connection to anything but loopback raises :class:`CassetteError`."""
    if not active:
        yield
        return
    connect, connect_ex = socket.socket.connect, socket.socket.connect_ex

    def _guard(sock: socket.socket, address: Any) -> None:
        if not _is_loopback(sock, address):
            raise CassetteError(
                f"address={address!r}: the network is blocked in record mode 'none' (replay "
                "only); only loopback is reachable. Record with --emrd-record-mode=once to "
                "allow live requests."
            )

    def guarded_connect(sock: socket.socket, address: Any) -> None:
        _guard(sock, address)
        connect(sock, address)

    def guarded_connect_ex(sock: socket.socket, address: Any) -> int:
        _guard(sock, address)
        return connect_ex(sock, address)

    socket.socket.connect = guarded_connect  # type: ignore[method-assign]
    socket.socket.connect_ex = guarded_connect_ex  # type: ignore[method-assign]
    try:
        yield
    finally:
        socket.socket.connect = connect  # type: ignore[method-assign]
        socket.socket.connect_ex = connect_ex  # type: ignore[method-assign]
