"""``emrd bench report``: a full report (every table and figure) for a 240-episode grid.

The grid is one model x 3 conditions x 4 spawns x 20 episodes of 50 steps from
:mod:`pytest_emrd.metrics.synthetic`, generated once and not timed. Timed: building the
report from the trajectories (episode metrics, every aggregate, representative reasoning when
the ``nlp`` extra is installed) and rendering Markdown + PNG figures, HTML and JSON in memory.
The sentence encoder is loaded during the warm-up, so its one-off start-up is not timed.
"""

from __future__ import annotations

from pytest_emrd.bench import Figure, median_seconds
from pytest_emrd.metrics.synthetic import synthetic_grid
from pytest_emrd.report import build_report, render_files
from pytest_emrd.trajectory import Trajectory

TARGET_GRID_240_S = 3.0


def full_report(trajectories: list[Trajectory]) -> dict[str, bytes]:
    """Every file ``emrd report`` writes, as bytes."""
    return render_files(build_report(trajectories))


def run(*, repeat: int) -> list[Figure]:
    grid = synthetic_grid()
    seconds = median_seconds(lambda: full_report(grid), repeat=repeat)
    return [Figure("report.grid_240_s", seconds, "s", TARGET_GRID_240_S, repeat)]
