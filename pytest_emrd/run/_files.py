"""Reading the episodes of several run directories (shards) from disk, and measuring them."""

from __future__ import annotations

import os
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING

from pytest_emrd._fork import available_cores, fork_map
from pytest_emrd.errors import ConfigError
from pytest_emrd.run._store import StoredEpisode, iter_run_episodes
from pytest_emrd.trajectory import Trajectory

if TYPE_CHECKING:
    from pytest_emrd.metrics import EpisodeMetrics


def load_run_episodes(run_dirs: Sequence[Path]) -> list[StoredEpisode]:
    """The episodes of several run directories (shards), sorted by case id; the first copy of
    a case wins. Each is read from its head (its trajectory decoded on first use,
    :func:`~pytest_emrd.run.read_episode`)."""
    seen: dict[str, StoredEpisode] = {}
    for run_dir in run_dirs:
        if not (run_dir / "episodes").is_dir():
            raise ConfigError(
                f"run_dir={str(run_dir)!r} holds no episodes/ folder; pass the directories "
                "that `pytest benchmarks --emrd-results DIR` wrote."
            )
        for stored in iter_run_episodes(run_dir):
            seen.setdefault(stored.head.spec.case_id, stored)
    return [seen[key] for key in sorted(seen)]


def load_run_dirs(run_dirs: Sequence[Path]) -> list[Trajectory]:
    """Trajectories of several run directories (shards); the first copy of a case wins."""
    return [stored.trajectory for stored in load_run_episodes(run_dirs)]


def measure_episodes(
    episodes: Sequence[StoredEpisode], processes: int | None = None
) -> list[EpisodeMetrics]:
    """Each episode's :func:`~pytest_emrd.metrics.episode_metrics`, in order, decoded and
    measured in ``processes`` forked workers (default: every available core, one inside an
    xdist worker, whose siblings hold the other cores). Decoding and measuring are most of
    the time of a gate over stored episodes, and episodes are independent."""
    if processes is None:
        processes = 1 if os.environ.get("PYTEST_XDIST_WORKER") else available_cores()
    return fork_map(_measure, episodes, processes)


def _measure(stored: StoredEpisode) -> EpisodeMetrics:
    from pytest_emrd.metrics import episode_metrics

    return episode_metrics(stored.decode_trajectory())
