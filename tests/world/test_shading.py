"""The renderer's scalar rules on worked examples: fog weight by depth, the first row below
a continuous row, and the shade table's colours. Pixel identity: ``test_frame_identity.py``."""

from __future__ import annotations

import numpy as np

from pytest_emrd.world import condition_params
from pytest_emrd.world._render import first_row, fog_weight, shade_table


def test_fog_weight_and_first_row_worked_examples() -> None:
    depths = np.array([0.0, 3.5, 5.25, 7.0, 14.0])  # a reach of 7 m: 255 * (d / 7)^4
    assert fog_weight(depths, 7.0).tolist() == [0, 16, 81, 255, 255]
    # Row r's centre lies at r + 0.5: row 9's is at 9.5, row 10's is the first below 9.6.
    rows = first_row(np.array([9.5, 9.6, 10.5, -3.0, 600.0]))
    assert rows.tolist() == [9, 10, 10, 0, 512]


def test_shade_table_worked_example() -> None:
    """White under baseline light: a lit top at fog 0 is white, an x face 74 % of it
    (188.7 -> 189), and at full fog every face is the fog colour. Every entry names the
    object its label paints (the room's labels: 0), whatever the fog."""
    params = condition_params("baseline")
    colors = np.array([[255, 255, 255], [0, 0, 0], [255, 255, 255]])
    table = shade_table(colors, params, np.array([0, 8, 9]))
    rgb, owner = (table & 0xFFFFFF).reshape(3, 4, 256), (table >> 24).reshape(3, 4, 256)
    assert table.dtype == np.uint32
    assert rgb[0, 2, 0] == 0xFFFFFF
    assert rgb[0, 0, 0] == 189 | 189 << 8 | 189 << 16
    r, g, b = params.fog_color
    assert (rgb[:, :, 255] == r | g << 8 | b << 16).all()
    assert (owner == np.array([0, 8, 9])[:, None, None]).all()
