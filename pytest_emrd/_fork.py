"""Forked worker processes for pure computations that can run beside the rest.

On a machine with cores to spare, parts of reports and gates run in workers forked from this
process (its modules imported, its data in memory), each part computed once by the same code.
Forking is used only where it is safe (Linux, no other thread alive); elsewhere all runs here.
"""

from __future__ import annotations

import multiprocessing
import os
import sys
import threading
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import ProcessPoolExecutor
from contextlib import contextmanager
from multiprocessing.context import BaseContext
from typing import TypeVar

T = TypeVar("T")
U = TypeVar("U")


def available_cores() -> int:
    """The cores this process may run on (its CPU affinity where the OS tells it)."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # macOS, Windows
        return os.cpu_count() or 1


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


def fork_map(fn: Callable[[T], U], items: Sequence[T], processes: int) -> list[U]:
    """``[fn(item) for item in items]``, in order, shared among ``processes`` forked workers
    (each taking a few contiguous chunks, so a slow item does not hold the others), or
    computed here where forking is unsafe, ``processes`` < 2 or there are fewer than two
    items. ``fn`` must be a module-level function; items and results travel by pickle."""
    workers = pool(min(processes, len(items)))
    if workers is None:
        return [fn(item) for item in items]
    with workers:
        return list(workers.map(fn, items, chunksize=max(1, len(items) // (4 * processes))))
