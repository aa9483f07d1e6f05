"""Work done in forked worker processes gives the same report and the same figure bytes."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from pathlib import Path

import pytest

from pytest_emrd.metrics.synthetic import synthetic_grid
from pytest_emrd.report import build_report
from pytest_emrd.report._plots import render_figures
from pytest_emrd.run import StoredEpisode, load_run_episodes
from pytest_emrd.trajectory import Trajectory


@pytest.fixture
def episodes(make_run_dir: Callable[[str, Sequence[Trajectory]], Path]) -> list[StoredEpisode]:
    grid = synthetic_grid(model="scout", episodes=1, max_steps=26)
    return load_run_episodes([make_run_dir("run", grid)])


def test_figures_drawn_in_worker_processes_are_the_same_bytes(episodes) -> None:
    report = build_report(episodes, with_reasoning=False)
    one, two = render_figures(report), render_figures(report, processes=2)
    assert two == one
    assert list(two[0]) == list(one[0])  # in FIGURES order


def test_map_aligned_in_a_worker_process_is_the_same_report(episodes) -> None:
    here = build_report(episodes, with_reasoning=False)
    assert build_report(episodes, with_reasoning=False, processes=2) == here
    assert here.episode_map is not None
