"""Bounded waiting on the Unity process: nothing this backend does may hang.

Every call into ``ai2thor`` (construction, reset, each step) runs in a daemon thread and
is abandoned after its time limit: a daemon thread cannot keep the interpreter alive, so
a Unity process that never answers costs at most the limit, never a hang.
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from typing import TypeVar

from pytest_emrd.errors import EmrdError

T = TypeVar("T")


class _Outcome:
    __slots__ = ("error", "value")

    def __init__(self) -> None:
        self.value: object = None
        self.error: BaseException | None = None


def bounded(fn: Callable[[], T], *, seconds: float, on_timeout: Callable[[], EmrdError]) -> T:
    """``fn()``, or the error ``on_timeout()`` builds if it has not returned in ``seconds``.

    Exceptions raised by ``fn`` propagate unchanged.
    """
    outcome = _Outcome()

    def target() -> None:
        try:
            outcome.value = fn()
        except BaseException as exc:  # handed to the caller's thread below
            outcome.error = exc

    worker = threading.Thread(target=target, name="emrd-thor-call", daemon=True)
    worker.start()
    worker.join(seconds)
    if worker.is_alive():
        raise on_timeout()
    if outcome.error is not None:
        raise outcome.error
    return outcome.value  # type: ignore[return-value]
