"""Live episodes computed ahead, several at once, in threads of one process
(``--emrd-concurrency N``): a live episode mostly waits for the model.

Episodes go through the results store in the order given; one stored already or locked by
another thread or process is skipped, so each is still computed once, and the tests read
them from the store as usual. HTTP traffic is routed per thread to each episode's own
cassette (:func:`pytest_emrd.cassette.routing`)."""

from __future__ import annotations

import contextlib
from collections.abc import Callable, Iterable
from concurrent.futures import ThreadPoolExecutor
from typing import TYPE_CHECKING

from pytest_emrd.errors import EmrdError
from pytest_emrd.run._settings import RunSettings
from pytest_emrd.run._store import ResultsStore
from pytest_emrd.trajectory import EpisodeSpec

if TYPE_CHECKING:
    from pytest_emrd.cassette import EpisodeRun


class Prefetcher:
    """Computes ``specs`` ahead with ``workers`` threads until :meth:`close`."""

    def __init__(
        self,
        store: ResultsStore,
        compute: Callable[[EpisodeSpec], EpisodeRun],
        specs: Iterable[EpisodeSpec],
        *,
        workers: int,
    ) -> None:
        from pytest_emrd.cassette import routing

        self._store, self._compute = store, compute
        self._exit = contextlib.ExitStack()
        self._exit.enter_context(routing())
        self._pool = ThreadPoolExecutor(workers, thread_name_prefix="emrd-episode")
        self._futures = [self._pool.submit(self._one, spec) for spec in specs]

    def _one(self, spec: EpisodeSpec) -> bool:
        try:
            return self._store.compute_if_free(spec, self._compute)
        except EmrdError:
            return False  # the test asking for this episode computes it and reports the error

    def wait(self) -> None:
        """Block until every episode was computed or skipped."""
        for future in self._futures:
            future.result()

    def close(self) -> None:
        """Drop the episodes not started, wait for the running ones, stop routing."""
        self._pool.shutdown(wait=True, cancel_futures=True)
        self._exit.close()


def start_prefetch(
    settings: RunSettings,
    store: ResultsStore,
    compute: Callable[[EpisodeSpec], EpisodeRun],
    specs: Iterable[EpisodeSpec],
    modality_of: Callable[[str], str] | None = None,
) -> Prefetcher | None:
    """A :class:`Prefetcher` of the live episodes among ``specs`` (those whose cassette will
    be recorded), or None when ``--emrd-concurrency`` is 1 or every episode replays (then the
    cassette stage is not even imported: a resumed run reads everything from the store)."""
    if settings.concurrency <= 1 or settings.replays_only:
        return None
    from pytest_emrd.cassette import is_live

    live = [
        s
        for s in specs
        if is_live(
            s,
            cassettes=settings.cassettes,
            record_mode=settings.record_mode,
            modality_of=modality_of,
        )
    ]
    if not live:
        return None
    return Prefetcher(store, compute, live, workers=settings.concurrency)
