"""The renderer's compiled pixel stage loads lazily: numba is imported by the first frame,
never by importing the package, the plugin or the CLI (collection stays free of it)."""

from __future__ import annotations

import subprocess
import sys

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
