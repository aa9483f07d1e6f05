"""Visibility read off the frame: field of view, walls and furniture hide what the frame
does not show, doorways do not; landmarks reach as far as the frame draws them legibly."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from pytest_emrd.world import (
    ConditionParams,
    Layout,
    Room,
    WorldObject,
    WorldPose,
    condition_params,
    discoverable_ids,
    paper_office,
)
from pytest_emrd.world._render import render, shade_table
from pytest_emrd.world._scene import scene_of
from pytest_emrd.world._visibility import in_view

BASELINE = condition_params("baseline")
WIDE = dataclasses.replace(BASELINE, visibility_distance=7.0)
"""Baseline with objects legible across the two-room layout (the geometry tests)."""


def _look(layout: Layout, pose: WorldPose, params: ConditionParams = WIDE):
    scene = scene_of(layout)
    frame, legible = render(scene, pose, params, shade_table(scene.colors, params, scene.owners))
    return frame, in_view(scene, pose, legible)


def _seen(layout: Layout, pose: WorldPose, params: ConditionParams = WIDE) -> list[str]:
    return [v.object_id for v in _look(layout, pose, params)[1]]


def _without(layout: Layout, object_id: str) -> Layout:
    return dataclasses.replace(
        layout, objects=tuple(o for o in layout.objects if o.object_id != object_id)
    )


def test_object_behind_a_wall_is_hidden_one_through_the_doorway_is_seen(
    two_rooms: Layout,
) -> None:
    # facing south from the Office: the fridge is straight through the doorway, the stool
    # is in the field of view and in range but behind the wall
    pose = WorldPose(3.0, 6.5, 180.0)
    assert _seen(two_rooms, pose) == ["Doorway_1", "Fridge_1"]
    frame = _look(two_rooms, pose)[0]
    assert np.array_equal(frame, _look(_without(two_rooms, "Stool_1"), pose)[0])


@pytest.mark.parametrize(
    "pose", [WorldPose(3.0, 6.5, 180.0), WorldPose(3.0, 3.5, 180.0), WorldPose(2.5, 2.0, 270.0)]
)
@pytest.mark.parametrize("condition", ["baseline", "low_light"])
def test_an_object_is_listed_iff_the_frame_without_it_differs_legibly(
    two_rooms: Layout, pose: WorldPose, condition: str
) -> None:
    """The rule, object by object: listed iff removing it changes 150+ pixels by 24+ levels."""
    params = condition_params(condition)
    frame, listing = _look(two_rooms, pose, params)
    for obj in two_rooms.objects:
        without = _look(_without(two_rooms, obj.object_id), pose, params)[0]
        changed = (np.abs(frame.astype(np.int16) - without).max(axis=2) >= 24).sum()
        assert (changed >= 150) == (obj.object_id in {v.object_id for v in listing}), obj


def test_nothing_behind_the_agent_is_seen(two_rooms: Layout) -> None:
    assert _seen(two_rooms, WorldPose(3.0, 6.5, 0.0)) == []


def test_inside_the_room_the_stool_is_seen_with_its_bearing(two_rooms: Layout) -> None:
    listing = _look(two_rooms, WorldPose(2.5, 2.0, 270.0))[1]
    stool = next(v for v in listing if v.object_id == "Stool_1")
    # facing west, south is on the left: negative bearing
    assert stool.bearing == pytest.approx(-30.5, abs=0.1)
    assert stool.distance == pytest.approx(np.hypot(1.7, 1.0), abs=0.01)
    assert all(-45 <= v.bearing <= 45 for v in listing)
    assert [v.object_id for v in listing] == sorted(v.object_id for v in listing)


def test_fog_hides_objects_beyond_the_visibility_distance_not_landmarks(
    two_rooms: Layout,
) -> None:
    far = WorldPose(3.0, 6.5, 180.0)  # the fridge's face 5.1 m away, the doorway 2.5 m
    assert _seen(two_rooms, far, BASELINE) == ["Doorway_1"]
    assert _seen(two_rooms, WorldPose(3.0, 7.6, 180.0), BASELINE) == ["Doorway_1"]  # 3.6 m
    near = WorldPose(3.0, 3.5, 180.0)  # the fridge's face 2.1 m away
    assert "Fridge_1" in _seen(two_rooms, near, BASELINE)
    low = condition_params("low_light")
    assert "Fridge_1" in _seen(two_rooms, near, low)
    assert _seen(two_rooms, far, low) == ["Doorway_1"]


def _behind_furniture(occluder: str, height: float, stool_z: float = 3.5) -> Layout:
    """One room, the agent at (3, 1) facing north; ``occluder`` (1.6 x 0.5 m) at (3, 2.5),
    a stool at (3, ``stool_z``) behind it."""
    objs = (
        WorldObject(occluder + "_1", occluder, "Office", "salient", 3.0, 2.5, 1.6, 0.5, height),
        WorldObject("Stool_1", "Stool", "Office", "clutter", 3.0, stool_z, 0.4, 0.4, 0.7),
    )
    room = Room("Office", 0.0, 0.0, 6.0, 6.0)
    return Layout(seed=-2, width=6.0, depth=6.0, rooms=(room,), doorways=(), objects=objs)


def test_tall_furniture_hides_what_stands_behind_it() -> None:
    pose = WorldPose(3.0, 1.0, 0.0)
    shelf = _behind_furniture("ShelvingUnit", 1.8)
    assert _seen(shelf, pose) == ["ShelvingUnit_1"]
    assert np.array_equal(_look(shelf, pose)[0], _look(_without(shelf, "Stool_1"), pose)[0])


def test_a_counter_hides_a_low_stool_but_not_one_the_eye_looks_down_on() -> None:
    pose = WorldPose(3.0, 1.0, 0.0)
    assert _seen(_behind_furniture("CounterTop", 0.92, stool_z=3.0), pose) == ["CounterTop_1"]
    # a metre behind it, the eye (1.5 m) looks over the counter onto the stool
    assert _seen(_behind_furniture("CounterTop", 0.92), pose) == ["CounterTop_1", "Stool_1"]
    assert _seen(_behind_furniture("CounterTop", 0.3), pose) == ["CounterTop_1", "Stool_1"]


def test_a_chair_hides_little() -> None:
    pose = WorldPose(3.0, 1.0, 0.0)
    assert _seen(_behind_furniture("Chair", 0.92), pose) == ["Chair_1", "Stool_1"]


def test_discoverable_ids_is_sorted_cached_and_complete_for_open_rooms(two_rooms: Layout) -> None:
    ids = discoverable_ids(two_rooms)
    assert ids == ("Doorway_1", "Fridge_1", "Stool_1")
    assert discoverable_ids(_behind_furniture("ShelvingUnit", 1.8)) == (
        "ShelvingUnit_1",
        "Stool_1",  # seen from beside the shelf
    )
    assert discoverable_ids(two_rooms) is ids


def test_discoverable_ids_of_the_office_are_its_objects(office: Layout) -> None:
    ids = discoverable_ids(office)
    assert list(ids) == sorted(ids)
    assert set(ids) <= {o.object_id for o in office.objects}
    assert {d.object_id for d in office.doorways} <= set(ids)
    assert len(ids) >= 0.9 * len(office.objects)


def test_every_object_of_the_paper_office_is_discoverable() -> None:
    assert len(discoverable_ids(paper_office())) == len(paper_office().objects)
