"""Vectorised seeded draws against the scalar draws they replace: the ``texture`` palette
is the same, bit for bit, as one ``integer`` call at a time made it; spawn poses of any
layout, room and seed lie on the room's spawn points, one point per episode."""

from __future__ import annotations

import numpy as np
from hypothesis import given
from hypothesis import strategies as st

from pytest_emrd.rooms import ROOM_SLUGS
from pytest_emrd.trajectory import EpisodeSpec
from pytest_emrd.world import condition_params, generate_layout, paper_office
from pytest_emrd.world._motion import SPAWN_POSES, is_free, spawn_points, spawn_pose
from pytest_emrd.world._render import palette
from pytest_emrd.world._rng import StableRng
from pytest_emrd.world._scene import FLOOR0, PART0, TILE0, WALL0, scene_of


def test_integer_worked_example() -> None:
    rng, again = StableRng(3), StableRng(3)
    draws = [rng.random() for _ in range(4)]
    assert [again.integer(20, 235) for _ in range(4)] == [
        20 + min(int(r * 216), 215) for r in draws
    ]


@given(st.integers(0, 30), st.integers(0, 10_000))
def test_texture_palette_is_the_one_draw_at_a_time_palette(layout_seed: int, seed: int) -> None:
    scene = scene_of(paper_office() if layout_seed == 0 else generate_layout(layout_seed))
    expected = scene.colors.astype(np.int64)
    rng = StableRng(seed * 7919 + 17)
    for label in range(WALL0, len(expected)):
        if not TILE0 <= label < PART0:
            expected[label] = [rng.integer(20, 235) for _ in range(3)]
    expected[TILE0:PART0] = np.maximum(expected[FLOOR0:TILE0] - 12, 0)
    got = palette(scene, condition_params("texture"), seed)
    assert got.dtype == expected.dtype and np.array_equal(got, expected)


@given(st.integers(0, 30), st.integers(0, 3), st.integers(0, 2**32 - 1))
def test_a_spawn_pose_stands_free_on_a_spawn_point_of_its_room(
    layout_seed: int, room: int, seed: int
) -> None:
    layout = paper_office() if layout_seed == 0 else generate_layout(layout_seed)
    scene, spawn_room = scene_of(layout), layout.rooms[room]
    pose = spawn_pose(scene, spawn_room, seed)
    assert (pose.x, pose.z) in spawn_points(scene, spawn_room)
    assert is_free(scene, spawn_room, pose.x, pose.z)
    assert pose.heading in (0.0, 90.0, 180.0, 270.0)
    assert spawn_pose(scene, spawn_room, seed) == pose


@given(st.integers(0, 30), st.integers(0, 3))
def test_the_first_20_episodes_of_a_room_stand_on_20_points(layout_seed: int, room: int) -> None:
    layout = paper_office() if layout_seed == 0 else generate_layout(layout_seed)
    scene, spawn_room = scene_of(layout), layout.rooms[room]
    assert len(set(spawn_points(scene, spawn_room))) >= SPAWN_POSES
    slug = ROOM_SLUGS[spawn_room.name]
    seeds = [EpisodeSpec("m", "baseline", slug, i).seed for i in range(SPAWN_POSES)]
    points = {(p.x, p.z) for p in (spawn_pose(scene, spawn_room, s) for s in seeds)}
    assert len(points) == SPAWN_POSES
