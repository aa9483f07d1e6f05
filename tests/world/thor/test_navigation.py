"""Teleport targets and visibility filtering, from THOR's grid and metadata."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from pytest_emrd.world import Doorway, Room, WorldPose
from pytest_emrd.world.thor import IdTable
from pytest_emrd.world.thor._simulator import (
    CLEARANCE,
    MAX_OFF_AXIS,
    bearing,
    entry,
    grid,
    viewpoint,
    visible_objects,
    wrap180,
)

ROOM = Room("Office", 0.0, 0.0, 4.0, 4.0)
EAST = Room("Conference Room", 4.0, 0.0, 8.0, 4.0)


def _grid(x0: float, x1: float, z0: float, z1: float) -> np.ndarray:
    xs, zs = np.meshgrid(np.arange(x0, x1 + 1e-9, 0.25), np.arange(z0, z1 + 1e-9, 0.25))
    return np.column_stack([xs.ravel(), zs.ravel()])


POINTS = _grid(0.25, 7.75, 0.25, 3.75)


@pytest.mark.parametrize(
    ("dx", "dz", "expected"),
    [(0, 1, 0.0), (1, 0, 90.0), (0, -1, 180.0), (-1, 0, 270.0), (1, 1, 45.0)],
    ids=["north", "east", "south", "west", "north-east"],
)
def test_heading_is_clockwise_from_north(dx: float, dz: float, expected: float) -> None:
    assert bearing(WorldPose(5.0, 5.0, 0.0), 5.0 + dx, 5.0 + dz) % 360 == pytest.approx(expected)


def test_bearing_is_negative_to_the_left() -> None:
    facing_north = WorldPose(0.0, 0.0, 0.0)
    assert bearing(facing_north, -1.0, 1.0) == pytest.approx(-45.0)
    assert bearing(facing_north, 1.0, 1.0) == pytest.approx(45.0)


def test_grid_reads_thor_reachable_positions() -> None:
    assert grid([{"x": 1.0, "y": 0.9, "z": 2.5}]).tolist() == [[1.0, 2.5]]
    assert grid([]).shape == (0, 2)


def test_viewpoint_stays_in_the_target_room_and_faces_it() -> None:
    pose = viewpoint(POINTS, 3.9, 2.0, ROOM)  # desk against the Office's east wall
    assert pose is not None
    assert ROOM.contains(pose.x, pose.z)
    assert pose.heading == 90.0
    assert CLEARANCE <= np.hypot(3.9 - pose.x, 2.0 - pose.z) < CLEARANCE + 0.5


def test_viewpoint_without_reachable_positions_in_the_room_is_none() -> None:
    assert viewpoint(_grid(4.25, 7.75, 0.25, 3.75), 2.0, 2.0, ROOM) is None
    assert viewpoint(np.empty((0, 2)), 2.0, 2.0, ROOM) is None


@given(x=st.floats(0.3, 3.7), z=st.floats(0.3, 3.7))
def test_viewpoint_keeps_any_target_well_inside_the_view(x: float, z: float) -> None:
    pose = viewpoint(POINTS, x, z, ROOM)
    assert pose is not None and ROOM.contains(pose.x, pose.z)
    assert pose.heading in (0.0, 90.0, 180.0, 270.0)
    if np.hypot(x - pose.x, z - pose.z) >= CLEARANCE:
        assert abs(bearing(pose, x, z)) <= MAX_OFF_AXIS + 1e-9


@pytest.mark.parametrize(
    ("into", "heading"), [(EAST, 90.0), (ROOM, 270.0)], ids=["eastwards", "westwards"]
)
def test_entry_lands_past_the_doorway_facing_into_the_room(into: Room, heading: float) -> None:
    door = Doorway("Doorway_1", "Office", "Conference Room", 4.0, 2.0, 1.0, "z")
    pose = entry(POINTS, door, into)
    assert pose is not None and into.contains(pose.x, pose.z)
    assert pose.heading == heading
    assert abs(pose.x - 4.0) >= CLEARANCE
    assert abs(pose.z - 2.0) <= 0.25


def _meta(
    oid: str,
    x: float,
    z: float,
    *,
    visible: bool = True,
    distance: float = 2.0,
    size: tuple[float, float] = (0.5, 0.5),
) -> dict:
    return {
        "objectId": oid,
        "objectType": oid.split("|")[0],
        "position": {"x": x, "y": 0.5, "z": z},
        "visible": visible,
        "distance": distance,
        "axisAlignedBoundingBox": {
            "center": {"x": x, "y": 0.5, "z": z},
            "size": {"x": size[0], "y": 1.0, "z": size[1]},
        },
    }


def test_visible_objects_filters_maps_and_sorts() -> None:
    ids = IdTable({"Desk|1|0": "Desk_1", "door|1|2": "Doorway_1", "Chair|1|1": "Chair_1"})
    types = {"Desk_1": "Desk", "Doorway_1": "Doorway", "Chair_1": "Chair"}
    agent = WorldPose(0.0, 0.0, 0.0)
    seen = visible_objects(
        [
            _meta("door|1|2", 5.0, 0.5),  # centre outside the view: bearing clipped to 45
            _meta("Desk|1|0", -1.0, 2.0),
            _meta("Chair|1|1", 0.0, 1.0, visible=False),
            _meta("Wall|1|0", 0.0, 1.0),  # not ours
        ],
        agent,
        ids=ids,
        types=types,
        landmarks=frozenset({"Doorway_1"}),
        visibility_distance=3.3,
    )
    assert [(v.object_id, v.object_type, v.bearing) for v in seen] == [
        ("Desk_1", "Desk", pytest.approx(-26.6)),
        ("Doorway_1", "Doorway", 45.0),
    ]


def test_thor_s_visible_flag_decides_and_distance_is_horizontal() -> None:
    """Low light (3.5 m): a 2.8 m table whose near edge is 2.5 m away is visible to THOR
    (its visibility points lie within the distance, measured horizontally) although its
    pivot is 3.9 m away; it stays in the list, at its horizontal distance."""
    ids = IdTable({"DiningTable|2|0": "DiningTable_1"})
    agent = WorldPose(0.0, 0.0, 0.0)
    table = {
        **_meta("DiningTable|2|0", 0.0, 3.9, distance=4.05, size=(1.1, 2.8)),
        "position": {"x": 0.0, "y": 0.32, "z": 3.9},
    }
    (seen,) = visible_objects(
        [table],
        agent,
        ids=ids,
        types={"DiningTable_1": "DiningTable"},
        landmarks=frozenset(),
        visibility_distance=3.5,
    )
    assert (seen.object_id, seen.distance) == ("DiningTable_1", 3.9)


def test_landmarks_count_to_the_draw_distance_and_other_objects_to_the_visibility_distance() -> (
    None
):
    """THOR runs with the draw distance (7 m baseline); a chair 5 m away that THOR reports
    visible is dropped at the 3.3 m visibility distance, a doorway at the same place is kept,
    as in the builtin world."""
    ids = IdTable({"Chair|1|1": "Chair_1", "door|1|2": "Doorway_1"})
    types = {"Chair_1": "Chair", "Doorway_1": "Doorway"}
    agent = WorldPose(0.0, 0.0, 0.0)
    seen = visible_objects(
        [_meta("Chair|1|1", 0.0, 5.0), _meta("door|1|2", 0.5, 5.0)],
        agent,
        ids=ids,
        types=types,
        landmarks=frozenset({"Doorway_1"}),
        visibility_distance=3.3,
    )
    assert [v.object_id for v in seen] == ["Doorway_1"]


def test_wrap180_wraps_into_half_open_interval() -> None:
    assert wrap180(180.0) == -180.0
    assert wrap180(-190.0) == 170.0
