"""Visibility: field of view, distance, walls and furniture occlude, doorways do not;
landmarks are seen as far as the frame draws; frames agree."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from pytest_emrd.errors import EmrdError
from pytest_emrd.world import (
    Layout,
    Room,
    WorldObject,
    WorldPose,
    _visibility,
    condition_params,
    discoverable_ids,
    paper_office,
)
from pytest_emrd.world._render import palette, render, shade_table
from pytest_emrd.world._scene import scene_of
from pytest_emrd.world._visibility import sight

BASELINE = condition_params("baseline").visibility_distance
WIDE = 7.0
"""A distance that reaches across the two-room layout (the geometry tests)."""


def _seen(
    layout: Layout, pose: WorldPose, visibility: float = WIDE, landmarks: float | None = None
) -> list[str]:
    scene = scene_of(layout)
    return [v.object_id for v in sight(scene, pose, visibility, landmarks).listing(scene)]


def test_object_behind_a_wall_is_hidden_one_through_the_doorway_is_seen(
    two_rooms: Layout,
) -> None:
    # facing south from the Office: the fridge is straight through the doorway, the stool
    # is in the field of view and in range but behind the wall
    assert _seen(two_rooms, WorldPose(3.0, 6.5, 180.0)) == ["Doorway_1", "Fridge_1"]


def test_nothing_behind_the_agent_is_seen(two_rooms: Layout) -> None:
    assert _seen(two_rooms, WorldPose(3.0, 6.5, 0.0)) == []


def test_inside_the_room_the_stool_is_seen_with_its_bearing(two_rooms: Layout) -> None:
    scene = scene_of(two_rooms)
    listing = sight(scene, WorldPose(2.5, 2.0, 270.0), WIDE).listing(scene)
    stool = next(v for v in listing if v.object_id == "Stool_1")
    # facing west, south is on the left: negative bearing
    assert stool.bearing == pytest.approx(-30.5, abs=0.1)
    assert stool.distance == pytest.approx(np.hypot(1.7, 1.0), abs=0.01)
    assert all(-45 <= v.bearing <= 45 for v in listing)
    assert [v.object_id for v in listing] == sorted(v.object_id for v in listing)


def test_visibility_distance_limits_objects_and_the_drawn_distance_landmarks(
    two_rooms: Layout,
) -> None:
    far = WorldPose(3.0, 7.6, 180.0)  # fridge centre 6.6 m away, doorway 3.6 m
    assert _seen(two_rooms, far) == ["Doorway_1", "Fridge_1"]
    base, low = condition_params("baseline"), condition_params("low_light")
    assert _seen(two_rooms, far, base.visibility_distance, base.draw_distance) == ["Doorway_1"]
    assert _seen(two_rooms, far, low.visibility_distance, low.draw_distance) == []
    near = WorldPose(3.0, 4.5, 180.0)  # the fridge's near samples 3.2 m away
    assert _seen(two_rooms, near, base.visibility_distance) == ["Doorway_1", "Fridge_1"]


def _behind_furniture(occluder: str, height: float, stool_z: float = 3.5) -> Layout:
    """One room, the agent at (3, 1) facing north; ``occluder`` (1.6 x 0.5 m) at (3, 2.5),
    a stool at (3, ``stool_z``) behind it."""
    objs = (
        WorldObject(occluder + "_1", occluder, "Office", "salient", 3.0, 2.5, 1.6, 0.5, height),
        WorldObject("Stool_1", "Stool", "Office", "clutter", 3.0, stool_z, 0.4, 0.4, 0.7),
    )
    room = Room("Office", 0.0, 0.0, 6.0, 6.0)
    return Layout(seed=-2, width=6.0, depth=6.0, rooms=(room,), doorways=(), objects=objs)


def test_tall_furniture_hides_what_stands_behind_it_in_the_list_and_the_frame() -> None:
    pose = WorldPose(3.0, 1.0, 0.0)
    shelf = _behind_furniture("ShelvingUnit", 1.8)
    assert _seen(shelf, pose) == ["ShelvingUnit_1"]
    assert np.array_equal(_frame(shelf, pose), _frame(_without(shelf, "Stool_1"), pose))


def test_a_counter_hides_a_low_stool_but_not_what_rises_above_the_line_over_it() -> None:
    pose = WorldPose(3.0, 1.0, 0.0)
    # right behind the counter the line to the stool's top (0.7 m) passes below its top
    counter = _behind_furniture("CounterTop", 0.92, stool_z=3.0)
    assert _seen(counter, pose) == ["CounterTop_1"]
    assert np.array_equal(_frame(counter, pose), _frame(_without(counter, "Stool_1"), pose))
    # a metre behind it, the eye (1.5 m) looks over the counter onto the stool
    assert _seen(_behind_furniture("CounterTop", 0.92), pose) == ["CounterTop_1", "Stool_1"]
    low_rail = _behind_furniture("CounterTop", 0.3)
    assert _seen(low_rail, pose) == ["CounterTop_1", "Stool_1"]
    assert not np.array_equal(_frame(low_rail, pose), _frame(_without(low_rail, "Stool_1"), pose))


def test_chairs_and_plants_hide_nothing() -> None:
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


def _frame(layout: Layout, pose: WorldPose) -> np.ndarray:
    scene, params = scene_of(layout), condition_params("baseline")
    return render(scene, pose, params, shade_table(palette(scene, params, 0), params))


def _without(layout: Layout, object_id: str) -> Layout:
    return dataclasses.replace(
        layout, objects=tuple(o for o in layout.objects if o.object_id != object_id)
    )


def test_frame_agrees_with_visibility(two_rooms: Layout) -> None:
    pose = WorldPose(3.0, 6.5, 180.0)
    frame = _frame(two_rooms, pose)
    assert np.array_equal(frame, _frame(_without(two_rooms, "Stool_1"), pose))  # behind a wall
    assert not np.array_equal(frame, _frame(_without(two_rooms, "Fridge_1"), pose))


def test_sights_are_kept_per_scene_and_read_only(
    two_rooms: Layout, office: Layout, monkeypatch: pytest.MonkeyPatch
) -> None:
    scene = scene_of(two_rooms)
    pose = WorldPose(3.0, 6.5, 180.0)
    seen = sight(scene, pose, BASELINE)
    assert sight(scene, WorldPose(3.0, 6.5, 180.0), BASELINE) is seen
    assert sight(scene, pose, 3.5) is not seen  # another visibility distance
    assert sight(scene, pose, BASELINE, 7.0) is not seen  # another landmark distance
    assert seen.listing(scene) is seen.listing(scene)
    assert not seen.mask.flags.writeable and not seen.distance.flags.writeable
    with pytest.raises(EmrdError, match="another scene"):
        seen.listing(scene_of(office))
    monkeypatch.setattr(_visibility, "SIGHT_MEMO", 3)
    for x in (1.0, 1.5, 2.0, 2.5):  # four new poses: the oldest kept ones are dropped
        sight(scene, WorldPose(x, 6.5, 180.0), BASELINE)
    assert len(scene.sights) == 3
    assert sight(scene, pose, BASELINE) is not seen
    assert sight(scene, pose, BASELINE).listing(scene) == seen.listing(scene)
