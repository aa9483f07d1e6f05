"""Per-episode metrics saved beside the results store's episodes (file I/O).

Layout, next to :mod:`pytest_emrd.run._store`'s::

    <run>/metrics/<case_id>.json    {"key": ..., "protocol": ..., "metrics": {...}}

A gate needs the per-episode metrics of every episode of its cell, and the gates of one cell
run in several xdist workers and again in every resumed run. Each episode's metrics are
computed once, by whichever process first needs them, and read back by everyone else: a
resumed run evaluates its gates without rebuilding a single trajectory.

A saved file is used only while it still describes the stored episode: its ``key`` is the
SHA-256 of the episode file's bytes together with a fingerprint of the code that computes the
metrics (:func:`~pytest_emrd.run.code_fingerprint`), so a recomputed episode or changed metric
code is measured again. Errored episodes are never saved (the store retries them in a new session).
Saved files are scrubbed like the episodes (an episode's rationale is model text).
"""

from __future__ import annotations

import hashlib
import json
from collections.abc import Callable, Iterable, Sequence
from pathlib import Path
from typing import Any, Final, Generic, Protocol, TypeVar

from pytest_emrd._atomic import write_bytes_atomic
from pytest_emrd._scrub import scrub_bytes
from pytest_emrd.run._store import ResultsStore, StoredEpisode, episode_path
from pytest_emrd.trajectory import EpisodeSpec, Trajectory


class Measured(Protocol):
    """What a per-episode measure returns, e.g. :class:`~pytest_emrd.metrics.EpisodeMetrics`."""

    @property
    def spec(self) -> EpisodeSpec: ...

    @property
    def errored(self) -> bool: ...

    def to_dict(self) -> dict[str, Any]: ...


M = TypeVar("M", bound=Measured)

#: The code behind :func:`pytest_emrd.metrics.episode_metrics` (fingerprinted, not imported).
EPISODE_METRICS_CODE: Final = (
    "pytest_emrd.metrics",
    "pytest_emrd.trajectory",
    "pytest_emrd.rooms",
    "pytest_emrd._serde",
)
#: The numeric libraries it computes with (their versions enter the fingerprint).
EPISODE_METRICS_LIBRARIES: Final = ("numpy", "scipy")


def metrics_path(run_dir: Path, spec: EpisodeSpec) -> Path:
    """Where a run directory keeps ``spec``'s per-episode metrics."""
    return run_dir / "metrics" / f"{spec.case_id}.json"


def metrics_key(episode_file: bytes, code: str) -> str:
    """The key a saved measure is valid for: the episode file's bytes and the code's
    fingerprint."""
    return hashlib.sha256(episode_file + code.encode()).hexdigest()


def read_saved(
    run_dir: Path,
    spec: EpisodeSpec,
    *,
    code: str,
    protocol: str,
    load: Callable[[dict[str, Any]], M],
) -> M | None:
    """The measure saved in ``run_dir`` for the very episode file stored there now, under
    ``protocol`` and by the code fingerprinted as ``code``; None when missing, stale or
    unreadable (the caller measures again)."""
    try:
        episode_file = episode_path(run_dir, spec).read_bytes()
        document = json.loads(metrics_path(run_dir, spec).read_bytes())
        if document["key"] != metrics_key(episode_file, code):
            return None
        if document["protocol"] != protocol:
            return None
        measured = load(document["metrics"])
    except (OSError, ValueError, KeyError, TypeError):
        return None
    return measured if measured.spec == spec and not measured.errored else None


def measured_episodes(
    run_dirs: Sequence[Path],
    episodes: Iterable[Trajectory | StoredEpisode],
    *,
    measure: Callable[[Trajectory], M],
    load: Callable[[dict[str, Any]], M],
    code: str,
) -> list[M]:
    """The measure of each episode read from ``run_dirs`` (the first directory holding it,
    as :func:`~pytest_emrd.run.load_run_episodes` reads them): read back where the run saved
    it for that very episode file, measured otherwise (a stored episode's trajectory is
    decoded only then). Nothing is written: reading a run never changes it."""
    out = []
    for episode in episodes:
        facts = episode.head if isinstance(episode, StoredEpisode) else episode
        spec = facts.spec
        home = next((d for d in run_dirs if episode_path(d, spec).is_file()), None)
        saved = None if home is None else read_saved(
            home, spec, code=code, protocol=facts.protocol, load=load
        )  # fmt: skip
        if saved is None:
            trajectory = episode.trajectory if isinstance(episode, StoredEpisode) else episode
            saved = measure(trajectory)
        out.append(saved)
    return out


class MeasuredStore(Generic[M]):
    """Per-episode metrics of one results store, measured at most once per stored episode."""

    def __init__(
        self,
        store: ResultsStore,
        *,
        measure: Callable[[Trajectory], M],
        load: Callable[[dict[str, Any]], M],
        code: str,
    ) -> None:
        self.store = store
        self.measure, self.load, self.code = measure, load, code
        """``code``: the :func:`code_fingerprint` of ``measure``."""

    def path_for(self, spec: EpisodeSpec) -> Path:
        return metrics_path(self.store.run_dir, spec)

    def _key(self, episode_file: bytes) -> str:
        return metrics_key(episode_file, self.code)

    def saved(self, spec: EpisodeSpec) -> M | None:
        """The metrics saved for the very episode file stored now for ``spec``, or None."""
        return read_saved(
            self.store.run_dir, spec, code=self.code, protocol=self.store.protocol, load=self.load
        )

    def get(self, spec: EpisodeSpec, episode: Callable[[EpisodeSpec], StoredEpisode]) -> M:
        """The metrics of ``spec``'s stored episode: read back when saved for the very
        episode file now stored, else measured on ``episode(spec)`` (which computes or
        reads the episode through the store) and saved."""
        saved = self.saved(spec)
        if saved is not None:
            return saved
        trajectory = episode(spec).trajectory
        measured = self.measure(trajectory)
        if not measured.errored:
            document = {
                "key": self._key(self.store.path_for(spec).read_bytes()),
                "protocol": trajectory.protocol,
                "metrics": measured.to_dict(),
            }
            blob = json.dumps(document, separators=(",", ":")).encode()
            write_bytes_atomic(self.path_for(spec), scrub_bytes(blob, literal_only=True))
        return measured
