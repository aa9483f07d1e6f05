"""Reading the episodes of several run directories (shards) from disk."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

from pytest_emrd.errors import ConfigError
from pytest_emrd.run._store import StoredEpisode, iter_run_episodes
from pytest_emrd.trajectory import Trajectory


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
