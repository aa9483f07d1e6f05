"""Fixtures for the report tests: small synthetic runs, run directories, a fake encoder."""

from __future__ import annotations

import dataclasses
import hashlib
from collections.abc import Callable, Sequence
from pathlib import Path

import numpy as np
import pytest

from pytest_emrd.metrics.synthetic import synthetic_grid, synthetic_trajectory
from pytest_emrd.run import StoredEpisode
from pytest_emrd.trajectory import EpisodeSpec, Trajectory


def hashed_embed(texts: Sequence[str]) -> np.ndarray:
    """Deterministic bag-of-words vectors (stands in for the sentence encoder)."""
    out = np.zeros((len(texts), 32))
    for i, text in enumerate(texts):
        out[i, 0] = 1.0
        for word in text.lower().split():
            out[i, hashlib.sha256(word.encode()).digest()[0] % 31 + 1] += 1.0
    return out


@pytest.fixture(scope="session")
def embed() -> Callable[[Sequence[str]], np.ndarray]:
    return hashed_embed


@pytest.fixture(scope="session")
def grid() -> list[Trajectory]:
    """3 conditions x 4 spawns x 2 episodes of at most 30 steps (24 episodes)."""
    return synthetic_grid(model="syn", episodes=2, max_steps=30)


@pytest.fixture(scope="session")
def variant_grid(grid: list[Trajectory]) -> list[Trajectory]:
    """The grid plus B3 and no_inventory baseline episodes of the same model."""
    extra = [
        synthetic_trajectory(
            EpisodeSpec("syn", "baseline", spawn, e, variant=v, max_steps=30), seed=7
        )
        for v in ("B3", "no_inventory")
        for spawn in ("office", "kitchen", "conference", "entrance")
        for e in range(2)
    ]
    return grid + extra


@pytest.fixture(scope="session")
def as_errored() -> Callable[[Trajectory], Trajectory]:
    """The same episode, ended as ``errored`` by a transport failure."""

    def make(t: Trajectory) -> Trajectory:
        return dataclasses.replace(t, status="errored", error="TransportError: 503 after 5 tries")

    return make


@pytest.fixture
def make_run_dir(tmp_path: Path) -> Callable[[str, Sequence[Trajectory]], Path]:
    """Write trajectories as the results store does: ``<run>/episodes/<case_id>.json``."""

    def make(name: str, trajectories: Sequence[Trajectory]) -> Path:
        run = tmp_path / name
        (run / "episodes").mkdir(parents=True)
        for t in trajectories:
            stored = StoredEpisode.of(t, session="test", recorded=False, frame_drift=0, seconds=0.1)
            (run / "episodes" / f"{t.spec.case_id}.json").write_bytes(stored.to_json())
        return run

    return make
