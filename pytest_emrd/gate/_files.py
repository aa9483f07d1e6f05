"""Reading gate inputs from disk: thresholds files and run directories (file I/O only)."""

from __future__ import annotations

from collections.abc import Collection, Sequence
from pathlib import Path
from typing import Any, Final, Protocol

from pytest_emrd._yaml import read_text
from pytest_emrd.errors import ConfigError, EmrdError
from pytest_emrd.gate._store import StoredEpisode, iter_run_episodes
from pytest_emrd.gate._thresholds import Thresholds, parse_thresholds
from pytest_emrd.trajectory import Trajectory

#: How to make a model of one's own registry known to every run (ends unknown-model errors).
REGISTER_MODEL_HINT: Final = (
    " A model of your own registry must be registered for every run that reads this file:"
    " set `emrd_models = FILE` in the pytest ini (or pass --emrd-models FILE), and"
    " --models FILE to `emrd gate` and `emrd report`."
)


class RegistryLike(Protocol):
    def get(self, name: str) -> Any: ...

    def names(self) -> tuple[str, ...]: ...


def load_thresholds(path: Path, *, registry: RegistryLike, metrics: Collection[str]) -> Thresholds:
    """Read and validate a thresholds file against a model registry and metric names.

    Model names are checked with ``registry.get`` (so parametric names such as
    ``scout-decay-8`` are accepted); a missing file is a :class:`ConfigError`.
    """

    def is_model(name: str) -> bool:
        try:
            registry.get(name)
        except EmrdError:
            return False
        return True

    text = read_text(
        path, what="thresholds file", flag="--emrd-thresholds (emrd gate --thresholds)"
    )
    return parse_thresholds(
        text,
        source=str(path),
        is_model=is_model,
        model_names=registry.names(),
        metrics=metrics,
        unknown_model_hint=REGISTER_MODEL_HINT,
    )


def load_run_episodes(run_dirs: Sequence[Path]) -> list[StoredEpisode]:
    """The episodes of several run directories (shards), sorted by case id; the first copy of
    a case wins. Each is read through its head when it has one (trajectories decoded on first
    use, :func:`~pytest_emrd.gate.read_episode`)."""
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
