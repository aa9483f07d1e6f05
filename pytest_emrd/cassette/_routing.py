"""Several episode cassettes open at once in one process, one per thread.

vcrpy's ``use_cassette`` patches the HTTP libraries process-wide with functions bound to one
cassette, so two episodes recording at once in two threads would write into whichever
cassette was opened last. :func:`routing` patches them once, bound to a router that hands
each call to the cassette the calling thread opened (a context variable); while it is
active, :func:`~pytest_emrd.cassette.episode_cassette` loads, binds and saves its cassette
itself instead of patching. Loading, matching, recording and saving are vcrpy's own, so a
cassette written by concurrent episodes is byte for byte the one a lone episode writes.
"""

from __future__ import annotations

import contextlib
import importlib.util
import threading
from collections.abc import Iterator
from contextvars import ContextVar
from typing import Any, Final

from vcr.cassette import Cassette
from vcr.patch import CassettePatcherBuilder

from pytest_emrd.errors import CassetteError

#: vcrpy's patcher groups whose library is not installed. vcrpy tries (and fails) to import
#: each one again for every cassette it opens; skipping them patches exactly what it would.
ABSENT_PATCHERS: Final = tuple(
    group
    for group, module in (
        ("boto3", "botocore"),
        ("httplib2", "httplib2"),
        ("tornado", "tornado"),
        ("aiohttp", "aiohttp"),
        ("httpx2", "httpx2"),
    )
    if importlib.util.find_spec(module) is None
)

_current: ContextVar[Cassette | None] = ContextVar("emrd_cassette", default=None)
_lock = threading.Lock()
_depth = 0


class _Router:
    """Stands in for a cassette in vcrpy's patches; forwards to the thread's cassette."""

    custom_patches = ()
    skip_patchers = ABSENT_PATCHERS
    _path = "<emrd: the cassette of the calling thread>"

    def __getattr__(self, name: str) -> Any:
        cassette = _current.get()
        if cassette is None:
            raise CassetteError(
                "an HTTP request was made outside any episode while episodes run concurrently "
                "(--emrd-concurrency); make model requests only inside an episode."
            )
        return getattr(cassette, name)


def active() -> bool:
    """Whether :func:`routing` is in effect (episodes then bind their cassettes)."""
    return _depth > 0


@contextlib.contextmanager
def routing() -> Iterator[None]:
    """Patch the HTTP libraries once for the block, each request going to its thread's
    cassette (re-entrant: nested blocks share the one patch)."""
    global _depth
    with contextlib.ExitStack() as stack:
        with _lock:
            if _depth == 0:
                for patcher in CassettePatcherBuilder(_Router()).build():
                    stack.enter_context(patcher)
            _depth += 1
        try:
            yield
        finally:
            with _lock:
                _depth -= 1
                if _depth:
                    stack.pop_all()  # an outer block still needs the patches


@contextlib.contextmanager
def bound(cassette: Cassette) -> Iterator[Cassette]:
    """Route this thread's requests to ``cassette``; save it when the block succeeds (as
    vcrpy's ``use_cassette`` does with ``record_on_exception`` off)."""
    token = _current.set(cassette)
    try:
        yield cassette
    finally:
        _current.reset(token)
    cassette._save()
