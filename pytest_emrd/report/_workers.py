"""Forked worker processes for the parts of a report that are computed beside the rest.

A report is pure computation; on a machine with cores to spare some of it runs in worker
processes forked from this one (they start with its modules imported and its data in memory),
each part still computed once, by the same code, to the same result. Forking is used only
where it is safe (Linux, no other thread alive); elsewhere everything runs here.
"""

from __future__ import annotations

import multiprocessing
import sys
import threading
from collections.abc import Callable, Iterator
from concurrent.futures import ProcessPoolExecutor
from contextlib import contextmanager
from multiprocessing.context import BaseContext
from typing import TypeVar

T = TypeVar("T")


def fork_context() -> BaseContext | None:
    """The ``fork`` start method where forking is safe (Linux, no other thread alive), else
    None (compute here)."""
    safe = sys.platform == "linux" and threading.active_count() == 1
    return multiprocessing.get_context("fork") if safe else None


def pool(processes: int) -> ProcessPoolExecutor | None:
    """``processes`` forked workers, or None where forking is unsafe or ``processes`` < 2."""
    context = fork_context() if processes > 1 else None
    return None if context is None else ProcessPoolExecutor(processes, mp_context=context)


@contextmanager
def beside(fn: Callable[..., T], *args: object, fork: bool) -> Iterator[Callable[[], T]]:
    """``fn(*args)`` started in one forked worker while the caller goes on (when ``fork`` and
    forking is safe), else computed here; the function yielded returns the result."""
    context = fork_context() if fork else None
    if context is None:
        value = fn(*args)
        yield lambda: value
        return
    with ProcessPoolExecutor(1, mp_context=context) as worker:
        yield worker.submit(fn, *args).result
