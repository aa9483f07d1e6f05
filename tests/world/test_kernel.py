"""The renderer's compiled stage: numba loads with the first frame, never with the package,
the plugin or the CLI (collection stays free of it); its scalar helpers on worked examples.
Pixel identity: ``test_frame_identity.py``."""

from __future__ import annotations

import subprocess
import sys

from pytest_emrd.world._kernel import first_row, fog_weight

_PROBE = """
import sys
import pytest_emrd, pytest_emrd.cli, pytest_emrd.episode, pytest_emrd.plugin, pytest_emrd.world
from pytest_emrd.world import make_simulator, paper_office
sim = make_simulator("builtin")
before = "numba" in sys.modules
sim.reset(paper_office(), "baseline", "office", 1)
print(before, "numba" in sys.modules)
"""


def test_numba_is_imported_by_the_first_frame_not_by_the_package() -> None:
    out = subprocess.run(
        [sys.executable, "-c", _PROBE], capture_output=True, text=True, check=True
    ).stdout.split()
    assert out == ["False", "True"]


def test_fog_weight_and_first_row_worked_examples() -> None:
    baseline = (7.0, 0.25)  # visibility 7 m, a quarter fog at 7 m
    assert [fog_weight(d, baseline) for d in (0.0, 3.5, 7.0, 14.0, 28.0)] == [0, 16, 64, 255, 255]
    # Row r's centre lies at r + 0.5: row 9's is at 9.5, row 10's is the first below 9.6.
    assert [first_row(a, 512) for a in (9.5, 9.6, 10.5, -3.0, 600.0)] == [9, 10, 10, 0, 512]
