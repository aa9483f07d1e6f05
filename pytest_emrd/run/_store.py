"""The results store: one file per episode under a run directory (layout and locking:
docs/user-guide/running.md), computed at most once across processes and scrubbed of secrets.
An episode is reused when its spec and protocol match and it finished (an ``errored`` one
only within its own session, so a rerun retries failures). An episode's metrics are measured
once too and kept outside the run directory, beside its locks (:meth:`ResultsStore.metrics`).
"""

from __future__ import annotations

import functools
import hashlib
import json
import os
import platform
import secrets
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace
from functools import cached_property
from pathlib import Path
from typing import TYPE_CHECKING, Any, Final

from pytest_emrd import __version__
from pytest_emrd._files import write_bytes_atomic
from pytest_emrd._fork import available_cores, fork_map
from pytest_emrd._scrub import scrub, scrub_bytes
from pytest_emrd._serde import JsonRecord, Schema
from pytest_emrd.errors import ConfigError, ProtocolError
from pytest_emrd.run._identity import RunIdentity, run_lock, scratch_dir, write_identity
from pytest_emrd.trajectory import OLDER_SCHEMAS, SCHEMA_VERSION, EpisodeSpec, Trajectory, Usage

if TYPE_CHECKING:
    from filelock import FileLock

    from pytest_emrd.cassette import EpisodeRun
    from pytest_emrd.metrics import EpisodeMetrics

STORE_SCHEMA: Final = 2
#: The layout before heads moved into the episode file (read, never written).
LEGACY_STORE_SCHEMA: Final = 1
_COMPACT: Final = {"separators": (",", ":")}
#: What decoding a damaged, half-written or foreign stored file raises.
_DAMAGED: Final = (ValueError, KeyError, TypeError, ProtocolError)


HEAD_SCHEMA: Final = 1


@dataclass(frozen=True)
class EpisodeHead(JsonRecord):
    """The facts about a stored episode a run reads without decoding its trajectory: the first
    line of the episode file, written with the trajectory in one atomic write (it cannot
    describe another file); field names are the file's format."""

    schema = Schema(HEAD_SCHEMA, "episode head", "it is recomputed.")

    spec: EpisodeSpec
    protocol: str
    """World + prompt protocol version the episode ran under."""
    status: str
    """``terminated``, ``budget`` or ``errored``."""
    steps: int
    chosen_room: str | None
    final_map_entries: int
    """Entries of the terminal cognitive map (0: the map figure cannot show this episode)."""
    usage: Usage
    error: str | None
    """The stored (scrubbed) error text of an errored episode."""
    session: str
    recorded: bool
    """New model traffic was recorded for it (a live episode)."""
    frame_drift: int
    seconds: float
    retries: int
    schema_version: int = HEAD_SCHEMA

    @classmethod
    def of(
        cls,
        trajectory: Trajectory,
        *,
        session: str,
        recorded: bool,
        frame_drift: int,
        seconds: float,
        retries: int = 0,
    ) -> EpisodeHead:
        return cls(
            spec=trajectory.spec,
            protocol=trajectory.protocol,
            status=trajectory.status,
            steps=len(trajectory.steps),
            chosen_room=trajectory.chosen_room,
            final_map_entries=len(trajectory.final_map),
            usage=trajectory.usage,
            error=scrub(trajectory.error) if trajectory.error else trajectory.error,
            session=session,
            recorded=recorded,
            frame_drift=frame_drift,
            seconds=round(seconds, 3),
            retries=retries,
        )

    def describes(self, trajectory: Trajectory) -> bool:
        """Whether this head states what ``trajectory`` holds (how it was obtained aside)."""
        facts = {k: getattr(self, k) for k in ("session", "recorded", "frame_drift", "retries")}
        head = EpisodeHead.of(trajectory, seconds=self.seconds, **facts)
        return replace(head, error=self.error) == self


@dataclass(frozen=True)
class StoredEpisode:
    """An episode as the store holds it: its :class:`EpisodeHead` and its trajectory, which
    an episode read back from the store decodes from the file on first use."""

    head: EpisodeHead
    source: Trajectory | Path = field(repr=False, compare=False)
    """The trajectory itself, or the episode file holding it."""
    computed_now: bool = False

    @classmethod
    def of(cls, trajectory: Trajectory, **facts: Any) -> StoredEpisode:
        """``trajectory`` with the store's ``facts`` about it (:meth:`EpisodeHead.of`)."""
        return cls(EpisodeHead.of(trajectory, **facts), trajectory)

    @cached_property
    def trajectory(self) -> Trajectory:
        return self.decode_trajectory()

    def decode_trajectory(self) -> Trajectory:
        """The trajectory without keeping it (for a process that only measures the episode):
        the one held, else decoded from the file (:class:`ProtocolError` if it was replaced)."""
        if "trajectory" in self.__dict__:
            return self.trajectory
        if isinstance(self.source, Trajectory):
            return self.source
        path = self.source
        try:
            stored = StoredEpisode.from_json(path.read_bytes())
        except _DAMAGED as exc:
            raise _unreadable(path, exc) from exc
        if stored.head != self.head:
            raise ProtocolError(
                f"episode file={str(path)!r} changed while this run was reading it; rerun "
                "the run directory."
            )
        return stored.trajectory

    def to_json(self) -> bytes:
        """The stored file, configured key values removed everywhere and the error text (where
        our messages quote URLs and bodies) scrubbed of credentials."""
        trajectory = self.trajectory.to_dict()
        if trajectory.get("error"):
            trajectory["error"] = scrub(trajectory["error"])
        first = {
            "store_schema": STORE_SCHEMA,
            "trajectory_schema": trajectory["schema_version"],
            "head": self.head.to_dict(),
        }
        head, body = json.dumps(first, **_COMPACT)[:-1], json.dumps(trajectory, **_COMPACT)
        return scrub_bytes(f'{head},\n"trajectory":{body}}}\n'.encode(), literal_only=True)

    @classmethod
    def from_json(cls, blob: bytes) -> StoredEpisode:
        """A stored file, decoded and validated in full (its head describes its trajectory)."""
        document: dict[str, Any] = json.loads(blob)
        schema = document.get("store_schema")
        if schema not in (LEGACY_STORE_SCHEMA, STORE_SCHEMA) or isinstance(schema, bool):
            raise ProtocolError(
                f"store_schema={schema!r} is not one pytest-emrd {__version__} reads "
                f"({LEGACY_STORE_SCHEMA} or {STORE_SCHEMA})"
            )
        trajectory = Trajectory.from_dict(document["trajectory"])
        if schema == LEGACY_STORE_SCHEMA:
            return cls.of(
                trajectory,
                session=str(document["session"]),
                recorded=bool(document["recorded"]),
                frame_drift=int(document["frame_drift"]),
                seconds=float(document["seconds"]),
                retries=int(document.get("retries", 0)),
            )
        head = EpisodeHead.from_dict(document["head"])
        if not head.describes(trajectory):
            raise ProtocolError("its head does not describe its trajectory")
        return cls(head, trajectory)


def _unreadable(path: Path, exc: Exception) -> ProtocolError:
    return ProtocolError(
        f"episode file={str(path)!r} cannot be read ({exc}); delete it and rerun the run "
        "directory to recompute it."
    )


def episode_path(run_dir: Path, spec: EpisodeSpec) -> Path:
    """Where a run directory stores ``spec``'s episode.

    :param run_dir: The run directory.
    :param spec: The episode.
    :returns: The episode file's path.
    """
    return run_dir / "episodes" / f"{spec.case_id}.json"


def new_run_dir(parent: Path) -> Path:
    """A fresh, not yet created run directory name under ``parent`` (time + random suffix).

    :param parent: The folder of runs (``.emrd/runs``).
    :returns: The new directory's path.
    """
    return parent / f"{time.strftime('%Y%m%d-%H%M%S')}-{secrets.token_hex(3)}"


class ResultsStore:
    """Episodes of one run directory, computed at most once across processes.

    :param run_dir: The run directory.
    :param session: This pytest session's id (an episode errored in another session is retried).
    :param protocol: The protocol version a reusable episode must carry.
    :param identity: The grid and shard recorded before the first episode; None to record none.
    """

    def __init__(
        self, run_dir: Path, *, session: str, protocol: str, identity: RunIdentity | None = None
    ) -> None:
        self.run_dir, self.session, self.protocol = run_dir, session, protocol
        self.identity = identity  # recorded in run.json before the first episode is computed

    def reusable(self, spec: EpisodeSpec) -> StoredEpisode | None:
        """``spec``'s stored episode if reusable (same spec and protocol; finished, or errored
        in this session), else None."""
        try:
            stored = read_episode(episode_path(self.run_dir, spec))
        except (FileNotFoundError, *_DAMAGED):
            return None  # none yet, or unreadable leftovers (recomputed and overwritten)
        head = stored.head
        stale = head.spec != spec or head.protocol != self.protocol
        retried = head.status == "errored" and head.session != self.session
        return None if stale or retried else stored

    def holds(self, spec: EpisodeSpec) -> bool:
        """Whether the store has a reusable episode for ``spec``."""
        return self.reusable(spec) is not None

    def lock(self, spec: EpisodeSpec, *, timeout: float = -1) -> FileLock:
        """``spec``'s lock across processes, held while it is computed and saved (the run's
        identity is recorded in ``run.json`` before any episode is)."""
        if self.identity is not None:
            write_identity(self.run_dir, self.identity)
        return run_lock(self.run_dir, spec.case_id, timeout=timeout)

    def save(self, spec: EpisodeSpec, run: EpisodeRun) -> StoredEpisode:
        """Store ``run``, the episode of ``spec`` computed under its :meth:`lock`."""
        facts = {k: getattr(run, k) for k in ("recorded", "frame_drift", "seconds", "retries")}
        stored = StoredEpisode.of(run.trajectory, session=self.session, **facts)
        write_bytes_atomic(episode_path(self.run_dir, spec), stored.to_json())
        return replace(stored, computed_now=True)

    def get_or_compute(
        self,
        spec: EpisodeSpec,
        compute: Callable[[EpisodeSpec], EpisodeRun],
        *,
        measure: bool = False,
    ) -> StoredEpisode:
        """The stored episode for ``spec``, computed if needed (a reusable one is final); with
        ``measure``, its :meth:`metrics` are kept too, also once across processes (measured
        under the episode's lock, from the trajectory in memory when computed here)."""
        stored = self.reusable(spec)
        if stored is not None and (not measure or self._kept(stored.head).is_file()):
            return stored
        with self.lock(spec):
            stored = self.reusable(spec) or self.save(spec, compute(spec))
            if measure:
                self.metrics([stored])
        return stored

    def metrics(self, episodes: Sequence[StoredEpisode]) -> list[EpisodeMetrics]:
        """Each episode's metrics: read back where this store kept them for the same episode
        file and code, else measured (:func:`measure_episodes`) and kept.

        They are kept in the run's scratch folder (:func:`~pytest_emrd.run.scratch_dir`), so
        the run directory holds results only, keyed by the episode's head (which write of the
        episode file was measured) and by what measured it (this package's sources, Python's
        and numpy's versions): a rewritten episode or another pytest-emrd measures again.

        :param episodes: Stored episodes of this run directory.
        :returns: One :class:`~pytest_emrd.metrics.EpisodeMetrics` per episode, in order.
        """
        paths = [self._kept(stored.head) for stored in episodes]
        kept = {i: m for i, path in enumerate(paths) if (m := _read_kept(path)) is not None}
        missing = [i for i in range(len(episodes)) if i not in kept]
        measured = measure_episodes([episodes[i] for i in missing])
        if missing:  # private like the locks beside it
            paths[0].parent.parent.mkdir(mode=0o700, parents=True, exist_ok=True)
            paths[0].parent.mkdir(mode=0o700, exist_ok=True)
        for i, metrics in zip(missing, measured, strict=True):
            for other in paths[i].parent.glob(f"{episodes[i].head.spec.case_id}.*.json"):
                other.unlink(missing_ok=True)  # an earlier write's or code's: never read again
            write_bytes_atomic(paths[i], json.dumps(metrics.to_dict()).encode())
            kept[i] = metrics
        return [kept[i] for i in range(len(episodes))]

    def _kept(self, head: EpisodeHead) -> Path:
        """Where :meth:`metrics` keeps the metrics of the episode file with ``head``."""
        text = json.dumps(head.to_dict(), sort_keys=True).encode()
        key = hashlib.sha256(_code_key() + text).hexdigest()[:16]
        return scratch_dir(self.run_dir) / "metrics" / f"{head.spec.case_id}.{key}.json"


@functools.cache
def _code_key() -> bytes:
    """What measuring an episode depends on besides the episode: the sources of this package
    and the versions of Python and numpy (read once per process)."""
    import numpy

    root = Path(__file__).resolve().parents[1]
    digest = hashlib.sha256(f"{platform.python_version()} {numpy.__version__}".encode())
    for path in sorted(root.rglob("*.py")):
        digest.update(f"\0{path.relative_to(root).as_posix()}\0".encode() + path.read_bytes())
    return digest.digest()


def _read_kept(path: Path) -> EpisodeMetrics | None:
    """The metrics kept in ``path``; None if there are none (or unreadable: measured again)."""
    from pytest_emrd.metrics import EpisodeMetrics

    try:
        return EpisodeMetrics.from_dict(json.loads(path.read_bytes()))
    except (OSError, *_DAMAGED):
        return None


def read_episode(path: Path) -> StoredEpisode:
    """The episode stored in file ``path``: its head read from the first line, the trajectory
    decoded on first use (a file of the older layout: decoded and validated in full).

    :param path: An episode file of a run directory.
    :returns: The :class:`StoredEpisode`.
    """
    with path.open("rb") as file:
        first = file.readline()
        if first.endswith(b",\n"):
            document = json.loads(first[:-2] + b"}")
            store, trajectory = document.get("store_schema"), document.get("trajectory_schema")
            if store == STORE_SCHEMA and trajectory in (SCHEMA_VERSION, *OLDER_SCHEMAS):
                return StoredEpisode(EpisodeHead.from_dict(document["head"]), path)
        blob = first + file.read()
    return StoredEpisode.from_json(blob)


def load_run_episodes(run_dirs: Sequence[Path]) -> list[StoredEpisode]:
    """The episodes of several run directories (shards), read as :func:`read_episode` reads them
    and sorted by case id; the first copy of a case wins.

    :param run_dirs: The run directories, shards of one run or several runs.
    :returns: The :class:`StoredEpisode` list.
    """
    seen: dict[str, StoredEpisode] = {}
    for run_dir in run_dirs:
        if not (run_dir / "episodes").is_dir():
            raise ConfigError(
                f"run_dir={str(run_dir)!r} holds no episodes/ folder; pass the directories "
                "that `pytest benchmarks --emrd-results DIR` wrote."
            )
        for path in sorted((run_dir / "episodes").glob("*.json")):
            try:
                stored = read_episode(path)
            except _DAMAGED as exc:
                raise _unreadable(path, exc) from exc
            seen.setdefault(stored.head.spec.case_id, stored)
    return [seen[key] for key in sorted(seen)]


def load_run_dirs(run_dirs: Sequence[Path]) -> list[Trajectory]:
    """Trajectories of several run directories (shards); the first copy of a case wins.

    :param run_dirs: The run directories.
    :returns: The trajectories, sorted by case id (:func:`load_run_episodes`).
    """
    return [stored.trajectory for stored in load_run_episodes(run_dirs)]


def measure_episodes(
    episodes: Sequence[StoredEpisode], processes: int | None = None
) -> list[EpisodeMetrics]:
    """Each episode's :func:`~pytest_emrd.metrics.episode_metrics`, in order, decoded and
    measured in ``processes`` forked workers (default: every available core; one inside an
    xdist worker, whose siblings hold the other cores).

    :param episodes: The stored episodes.
    :param processes: Worker processes; None for the default above.
    :returns: One :class:`EpisodeMetrics` per episode.
    """
    if processes is None:
        processes = 1 if os.environ.get("PYTEST_XDIST_WORKER") else available_cores()
    return fork_map(_measure, episodes, processes)


def _measure(stored: StoredEpisode) -> EpisodeMetrics:
    from pytest_emrd.metrics import episode_metrics

    return episode_metrics(stored.decode_trajectory())
