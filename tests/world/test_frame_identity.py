"""Pixel identity of the renderer over many frames, pinned to WORLD_VERSION.

``frame_digests.json`` holds SHA-256 pixel digests (first 16 hex digits) of

* every frame of 24 committed scout episodes (``ep00`` and ``ep07`` of every condition and
  spawn room, the world-level actions taken from the committed cassettes), through the
  simulator as the episode loop drives it;
* a sweep of 1,280 frames: the paper office and the generated office of seed 7, every
  condition (``texture`` with three palette seeds), eight centimetre positions per room
  drawn by a seeded generator (some inside furniture, some against a wall), four headings
  (128 poses per office, rendered under five palettes).

The digests were recorded before the renderer was optimised, so a faster renderer that
changes one pixel of one frame fails here. If the world changes on purpose, bump
``WORLD_VERSION`` and record again: ``PYTHONPATH=$PWD python tests/world/test_frame_identity.py``.
"""

from __future__ import annotations

import hashlib
import json
from functools import cache
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pytest_emrd.trajectory import EpisodeSpec
from pytest_emrd.world import (
    WORLD_VERSION,
    Layout,
    WorldPose,
    condition_params,
    generate_layout,
    make_simulator,
    paper_office,
)
from pytest_emrd.world._render import palette, render, shade_table
from pytest_emrd.world._scene import scene_of

DATA = Path(__file__).with_name("frame_digests.json")
DIGITS = 16
LAYOUTS = {"paper": paper_office, "seed7": lambda: generate_layout(7)}
PALETTES = {"baseline": (3,), "low_light": (3,), "texture": (3, 11, 29)}
POSITIONS_PER_ROOM = 8


def _short(pixels: np.ndarray) -> str:
    return hashlib.sha256(pixels.data).hexdigest()[:DIGITS]


@cache
def _data() -> dict[str, Any]:
    data = json.loads(DATA.read_text())
    if data["world_version"] != WORLD_VERSION:
        pytest.fail(
            f"{DATA.name} is pinned to {data['world_version']}, the world is {WORLD_VERSION}; "
            "record it again (see this module's docstring)."
        )
    return data


def _poses(layout: Layout) -> list[WorldPose]:
    """Seeded centimetre positions in every room, each with the four headings."""
    rng = np.random.default_rng(20261122)
    poses = []
    for room in layout.rooms:
        xs = np.round(rng.uniform(room.x0 + 0.05, room.x1 - 0.05, POSITIONS_PER_ROOM), 2)
        zs = np.round(rng.uniform(room.z0 + 0.05, room.z1 - 0.05, POSITIONS_PER_ROOM), 2)
        poses += [
            WorldPose(float(x), float(z), float(h))
            for x, z in zip(xs, zs, strict=True)
            for h in (0, 90, 180, 270)
        ]
    return poses


def _sweep_keys() -> list[tuple[str, str, int]]:
    return [
        (lay, cond, seed) for lay in LAYOUTS for cond, seeds in PALETTES.items() for seed in seeds
    ]


def _key(key: tuple[str, str, int]) -> str:
    return "-".join(map(str, key))


def _sweep(layout_name: str, condition: str, seed: int) -> list[str]:
    layout = LAYOUTS[layout_name]()
    scene, params = scene_of(layout), condition_params(condition)
    table = shade_table(palette(scene, params, seed), params, scene.owners)
    return [_short(render(scene, pose, params, table)[0]) for pose in _poses(layout)]


def _episode(entry: dict[str, Any]) -> list[str]:
    """Digests of the reset frame and of every step's frame, as the episode loop sees them."""
    spec = EpisodeSpec("scout", entry["condition"], entry["spawn"], entry["episode"])
    sim = make_simulator("builtin")
    frames = [sim.reset(paper_office(), spec.condition, spec.spawn, spec.seed).frame]
    frames += [sim.step(action).frame for action in entry["actions"]]
    sim.close()
    return [_short(f) for f in frames]


def _case(entry: dict[str, Any]) -> str:
    return f"{entry['condition']}-{entry['spawn']}-ep{entry['episode']:02d}"


def _episodes() -> list[dict[str, Any]]:
    return json.loads(DATA.read_text())["episodes"]


@pytest.mark.parametrize("entry", _episodes(), ids=_case)
def test_every_frame_of_committed_episodes_is_unchanged(entry: dict[str, Any]) -> None:
    assert _episode(entry) == _data()["digests"][_case(entry)]


@pytest.mark.parametrize("key", _sweep_keys(), ids=_key)
def test_every_frame_of_the_pose_sweep_is_unchanged(key: tuple[str, str, int]) -> None:
    recorded = _data()["sweep"][_key(key)]
    assert len(recorded) == 4 * POSITIONS_PER_ROOM * 4
    assert _sweep(*key) == recorded


@settings(max_examples=40)
@given(
    st.lists(
        st.tuples(st.sampled_from(_sweep_keys()), st.integers(0, 4 * POSITIONS_PER_ROOM * 4 - 1)),
        min_size=1,
        max_size=6,
    )
)
def test_a_frame_does_not_depend_on_the_frames_drawn_before_it(
    draws: list[tuple[tuple[str, str, int], int]],
) -> None:
    """Whatever the renderer keeps between calls (buffers, per-scene tables), frames drawn
    in any order, across layouts and conditions, are the recorded ones."""
    for key, i in draws:
        layout_name, condition, seed = key
        layout = LAYOUTS[layout_name]()
        scene, params = scene_of(layout), condition_params(condition)
        table = shade_table(palette(scene, params, seed), params, scene.owners)
        frame = render(scene, _poses(layout)[i], params, table)[0]
        assert _short(frame) == _data()["sweep"][_key(key)][i]


def _record() -> None:
    data = json.loads(DATA.read_text())
    data["world_version"] = WORLD_VERSION
    data["digests"] = {_case(e): _episode(e) for e in data["episodes"]}
    data["sweep"] = {_key(k): _sweep(*k) for k in _sweep_keys()}
    DATA.write_text(json.dumps(data, indent=1) + "\n")


if __name__ == "__main__":
    _record()
