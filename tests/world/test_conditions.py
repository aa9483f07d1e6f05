"""Conditions: low light halves the light and darkens the fog, so less stands out from it;
texture recolours, moves nothing."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from pytest_emrd.errors import ConfigError
from pytest_emrd.world import Layout, condition_params

SCRIPT = ("Turn(Right)", "Turn(Right)", "Goto(Doorway_1)", "Turn(Around)", "Goto(Desk)")


def _episode(sim, layout: Layout, condition: str, seed: int = 4):
    return [sim.reset(layout, condition, "office", seed), *(sim.step(a) for a in SCRIPT)]


def _palette_of(frame: np.ndarray) -> np.ndarray:
    """The distinct colours of a frame, packed as ``0xRRGGBB``."""
    rgb = frame.reshape(-1, 3).astype(np.int64)
    return np.unique(rgb[:, 0] << 16 | rgb[:, 1] << 8 | rgb[:, 2])


def test_condition_table() -> None:
    base, low, tex = (condition_params(c) for c in ("baseline", "low_light", "texture"))
    assert base.visibility_distance == pytest.approx(3.25)
    assert base.draw_distance == pytest.approx(7.0)
    assert low.visibility_distance == base.visibility_distance  # darkness takes the contrast
    assert low.draw_distance == base.draw_distance  # landmarks keep their reach
    assert low.light_factor == pytest.approx(0.5 * base.light_factor)
    assert dataclasses.replace(tex, name="baseline", randomize_palette=False) == base
    assert tex.randomize_palette and not base.randomize_palette


def test_unknown_condition_names_the_choices() -> None:
    with pytest.raises(ConfigError, match=r"condition='smoke' is not one of 'baseline'"):
        condition_params("smoke")


def test_low_light_sees_less_and_is_clearly_darker(office: Layout, new_sim) -> None:
    base, low = _episode(new_sim(), office, "baseline"), _episode(new_sim(), office, "low_light")
    base_seen = sum(len(o.visible) for o in base)
    low_seen = sum(len(o.visible) for o in low)
    assert low_seen < base_seen
    for b, d in zip(base, low, strict=True):
        if b.pose == d.pose:
            assert {v.object_id for v in d.visible} <= {v.object_id for v in b.visible}
            assert all(v.distance <= 7.0 + 0.6 for v in d.visible)  # landmarks: drawn distance
            assert d.frame.mean() < 0.6 * b.frame.mean()


def test_low_light_fog_flattens_the_far_view(office: Layout, new_sim) -> None:
    base = new_sim().reset(office, "baseline", "office", 4).frame.astype(float)
    low = new_sim().reset(office, "low_light", "office", 4).frame.astype(float)
    band = slice(236, 276)  # rows around the horizon: the farthest surfaces in view
    assert low[band].std() < 0.5 * base[band].std()


def test_texture_changes_colours_but_no_positions(office: Layout, new_sim) -> None:
    base, tex = _episode(new_sim(), office, "baseline"), _episode(new_sim(), office, "texture")
    for b, t in zip(base, tex, strict=True):
        assert (b.pose, b.visible, b.success, b.feedback) == (
            t.pose,
            t.visible,
            t.success,
            t.feedback,
        )
        assert b.frame_digest != t.frame_digest
        assert not np.array_equal(_palette_of(b.frame), _palette_of(t.frame))
    ceiling = slice(0, 8)  # the ceiling keeps its colour: same rows, same pixels
    assert np.array_equal(base[0].frame[ceiling], tex[0].frame[ceiling])


def test_texture_is_seeded_per_episode(office: Layout, new_sim) -> None:
    a = _episode(new_sim(), office, "texture", seed=4)[0]
    b = _episode(new_sim(), office, "texture", seed=4)[0]
    c = new_sim().reset(office, "texture", "office", 5)
    assert a.frame_digest == b.frame_digest
    base_c = new_sim().reset(office, "baseline", "office", 5)
    assert c.pose == base_c.pose and c.frame_digest not in (a.frame_digest, base_c.frame_digest)
