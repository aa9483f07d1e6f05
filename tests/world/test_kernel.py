"""The renderer's compiled stage: numba loads with the first frame, never with the package,
the plugin or the CLI (collection stays free of it); its scalar helpers on worked examples;
the shade table against the numpy code it replaced. Pixel identity: ``test_frame_identity.py``."""

from __future__ import annotations

import dataclasses
import subprocess
import sys

import numpy as np
from hypothesis import given
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

from pytest_emrd.trajectory import CONDITIONS
from pytest_emrd.world import condition_params
from pytest_emrd.world._kernel import first_row, fog_weight
from pytest_emrd.world._render import FACE_LIGHT, shade_table

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


def _shade_table_oracle(colors: np.ndarray, params) -> np.ndarray:  # type: ignore[no-untyped-def]
    weight = np.arange(256, dtype=np.float64)
    lit = colors[:, None, None, :] * (FACE_LIGHT * params.light_factor)[None, :, None, None]
    mix = lit * ((255.0 - weight) / 255.0)[None, None, :, None]
    mix = mix + np.array(params.fog_color, dtype=np.float64) * (weight / 255.0)[:, None]
    rgb = np.clip(np.rint(mix), 0, 255).astype(np.uint32).reshape(-1, 3)
    return rgb[:, 0] | rgb[:, 1] << 8 | rgb[:, 2] << 16


@given(
    hnp.arrays(np.int64, st.tuples(st.integers(1, 12), st.just(3)), elements=st.integers(0, 255)),
    st.sampled_from(CONDITIONS),
    st.floats(0.0, 2.0),
    st.floats(0.0, 1.0),
    st.tuples(*[st.integers(0, 255)] * 3),
)
def test_shade_table_is_the_numpy_oracle_bit_for_bit(
    colors: np.ndarray, condition: str, light: float, fog: float, fog_color: tuple
) -> None:
    params = dataclasses.replace(
        condition_params(condition), light_factor=light, fog=fog, fog_color=fog_color
    )
    table = shade_table(colors, params)
    assert table.dtype == np.uint32
    assert table.tobytes() == _shade_table_oracle(colors, params).tobytes()


def test_shade_table_worked_example() -> None:
    """White under baseline light: a lit top at fog 0 is white, an x face 74 % of it
    (188.7 -> 189), and at full fog every face is the fog colour."""
    params = condition_params("baseline")
    table = shade_table(np.array([[255, 255, 255]]), params).reshape(4, 256)
    assert table[2, 0] == 0xFFFFFF
    assert table[0, 0] == 189 | 189 << 8 | 189 << 16
    r, g, b = params.fog_color
    assert (table[:, 255] == r | g << 8 | b << 16).all()
