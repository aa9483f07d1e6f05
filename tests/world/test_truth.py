"""Ground truth in the spawn frame: JSON round trip and a rigid world->spawn transform."""

from __future__ import annotations

import json
import math

import pytest
from hypothesis import given
from hypothesis import strategies as st

from pytest_emrd._serde import from_dict, to_dict
from pytest_emrd.trajectory import GroundTruth
from pytest_emrd.world import (
    Layout,
    WorldPose,
    discoverable_ids,
    ground_truth,
    heading_in_spawn_frame,
    to_spawn_frame,
)

coords = st.floats(min_value=-50, max_value=50, allow_nan=False)
headings = st.one_of(
    st.sampled_from([0.0, 90.0, 180.0, 270.0]), st.floats(0, 360, exclude_max=True)
)
poses = st.builds(WorldPose, coords, coords, headings)


@pytest.mark.parametrize(
    ("heading", "ahead", "right"),
    [(0, (0, 1), (1, 0)), (90, (1, 0), (0, -1)), (180, (0, -1), (-1, 0)), (270, (-1, 0), (0, 1))],
    ids=["north", "east", "south", "west"],
)
def test_spawn_frame_worked_examples(heading, ahead, right) -> None:
    spawn = WorldPose(2.0, 3.0, heading)
    assert to_spawn_frame(spawn, 2.0, 3.0) == (0.0, 0.0)
    assert to_spawn_frame(spawn, 2.0 + ahead[0], 3.0 + ahead[1]) == pytest.approx((0.0, 1.0))
    assert to_spawn_frame(spawn, 2.0 + right[0], 3.0 + right[1]) == pytest.approx((1.0, 0.0))
    assert heading_in_spawn_frame(spawn, heading + 90) == 90.0


@given(poses, coords, coords, coords, coords)
def test_spawn_frame_transform_is_a_rigid_motion(spawn, ax, az, bx, bz) -> None:
    a, b = to_spawn_frame(spawn, ax, az), to_spawn_frame(spawn, bx, bz)
    assert math.dist(a, b) == pytest.approx(math.hypot(ax - bx, az - bz), abs=1e-9)
    # a rotation, not a reflection: cross products (signed areas) are unchanged
    o = to_spawn_frame(spawn, 0.0, 0.0)
    cross_world = ax * bz - az * bx
    cross_spawn = (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])
    assert cross_spawn == pytest.approx(cross_world, rel=1e-9, abs=1e-6)


@given(poses, headings)
def test_heading_conversion_is_relative_to_spawn(spawn, heading) -> None:
    rel = heading_in_spawn_frame(spawn, heading)
    assert 0 <= rel < 360
    gap = (spawn.heading + rel - heading) % 360
    assert min(gap, 360 - gap) < 1e-9
    assert heading_in_spawn_frame(spawn, spawn.heading) == 0


def test_ground_truth_round_trips_through_json(office: Layout) -> None:
    truth = ground_truth(office, WorldPose(3.0, 7.0, 90.0), "office")
    again = from_dict(GroundTruth, json.loads(json.dumps(to_dict(truth))))
    assert again == truth
    assert truth.spawn_room == "Office"
    assert truth.discoverable_ids == discoverable_ids(office)


def test_ground_truth_is_the_layout_in_the_spawn_frame(office: Layout) -> None:
    spawn = WorldPose(3.0, 7.0, 270.0)
    truth = ground_truth(office, spawn, "Office")
    assert [o.object_id for o in truth.objects] == [o.object_id for o in office.objects]
    for gt, obj in zip(truth.objects, office.objects, strict=True):
        assert (gt.x, gt.z) == pytest.approx(to_spawn_frame(spawn, obj.x, obj.z), abs=1e-4)
        assert (gt.object_type, gt.room, gt.category) == (obj.object_type, obj.room, obj.category)
    office_outline = next(r for r in truth.rooms if r.name == "Office")
    room = office.room("Office")
    assert office_outline.polygon[0] == pytest.approx(to_spawn_frame(spawn, room.x0, room.z0))
    assert [r.name for r in truth.rooms] == [r.name for r in office.rooms]
