"""Fixtures of the viewer tests: one real scout episode on the builtin world."""

from __future__ import annotations

from pathlib import Path

import pytest

from pytest_emrd.episode import run_episode
from pytest_emrd.trajectory import EpisodeSpec, Trajectory


@pytest.fixture(scope="session")
def cassettes() -> Path:
    """The committed cassette folder."""
    return Path(__file__).parents[2] / "cassettes"


@pytest.fixture(scope="session")
def episode() -> Trajectory:
    """scout, baseline, office, episode 0: the committed cassette holds its frame digests."""
    traj = run_episode(EpisodeSpec("scout", "baseline", "office", 0, modality="both"))
    assert traj.status == "terminated", traj.error
    return traj
