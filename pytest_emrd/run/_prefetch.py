"""With ``--emrd-concurrency N``, live episodes computed ahead, ``N`` at once in threads (a live
episode mostly waits for the model); HTTP traffic is routed per thread to each episode's
cassette."""

from __future__ import annotations

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
    """Computes ``specs`` ahead with ``workers`` threads until :meth:`close`.

    :param store: The store the episodes are computed into.
    :param compute: Runs one episode.
    :param specs: The episodes to compute ahead.
    :param workers: Threads.
    """

    def __init__(
        self,
        store: ResultsStore,
        compute: Callable[[EpisodeSpec], EpisodeRun],
        specs: Iterable[EpisodeSpec],
        *,
        workers: int,
    ) -> None:
        self._store, self._compute = store, compute
        self._pool = ThreadPoolExecutor(workers, thread_name_prefix="emrd-episode")
        self._futures = [self._pool.submit(self._one, spec) for spec in specs]

    def _one(self, spec: EpisodeSpec) -> None:
        """Compute and save ``spec`` (never waits: stored or locked elsewhere is skipped)."""
        from filelock import Timeout

        try:
            with self._store.lock(spec, timeout=0):
                if self._store.reusable(spec) is None:
                    self._store.save(spec, self._compute(spec))
        except (Timeout, EmrdError):
            pass  # an error: the test asking for this episode computes it and reports it

    def wait(self) -> None:
        """Block until every episode was computed or skipped."""
        for future in self._futures:
            future.result()

    def close(self) -> None:
        """Drop the episodes not started, wait for the running ones."""
        self._pool.shutdown(wait=True, cancel_futures=True)


def start_prefetch(
    settings: RunSettings,
    store: ResultsStore,
    compute: Callable[[EpisodeSpec], EpisodeRun],
    specs: Iterable[EpisodeSpec],
    modality_of: Callable[[str], str] | None = None,
) -> Prefetcher | None:
    """A :class:`Prefetcher` of the live episodes among ``specs`` (those whose cassette will
    be recorded), or None when ``--emrd-concurrency`` is 1 or every episode replays (then the
    cassette stage is not even imported: a resumed run reads everything from the store).

    :param settings: The run's settings (concurrency, cassettes, record mode).
    :param store: Where finished episodes are written.
    :param compute: Runs one episode.
    :param specs: The episodes of this process.
    :param modality_of: Default modality per model; None for each spec's own.
    :returns: The started :class:`Prefetcher`, or None.
    """
    if settings.concurrency <= 1 or settings.replays_only:
        return None
    from pytest_emrd.cassette import is_live

    how = {"cassettes": settings.cassettes, "record_mode": settings.record_mode}
    live = [s for s in specs if is_live(s, **how, modality_of=modality_of)]
    return Prefetcher(store, compute, live, workers=settings.concurrency) if live else None
