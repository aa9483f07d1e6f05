"""The ProcTHOR house: well formed, faithful to the layout, deterministic."""

from __future__ import annotations

import json
import math
from dataclasses import replace
from typing import Any

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pytest_emrd.errors import ConfigError
from pytest_emrd.world._conditions import condition_params
from pytest_emrd.world._layout import generate_layout
from pytest_emrd.world._model import Doorway, Layout
from pytest_emrd.world.thor import SCHEMA, IdTable, build_house


def _inside(polygon: list[dict[str, float]], x: float, z: float) -> bool:
    xs, zs = [p["x"] for p in polygon], [p["z"] for p in polygon]
    return min(xs) <= x <= max(xs) and min(zs) <= z <= max(zs)


def _wall_length(wall: dict[str, Any]) -> float:
    a, b = wall["polygon"][0], wall["polygon"][1]
    return math.hypot(b["x"] - a["x"], b["z"] - a["z"])


def check_well_formed(house: dict[str, Any], layout: Layout) -> None:
    """Every structural promise a THOR build relies on when it loads the house."""
    assert house["metadata"]["schema"] == SCHEMA
    rooms = {r["id"]: r for r in house["rooms"]}
    walls = {w["id"]: w for w in house["walls"]}
    assert len(rooms) == len(house["rooms"]) and len(walls) == len(house["walls"])
    for wall in house["walls"]:
        assert wall["roomId"] in rooms
    for door in house["doors"]:
        assert door["room0"] in rooms and door["room1"] in rooms
        wall0, wall1 = walls[door["wall0"]], walls[door["wall1"]]
        assert wall0["roomId"] == door["room0"]
        # the two faces are the same piece of wall (ProcTHOR's order-free position key)
        assert door["wall0"].split("|")[2:] == door["wall1"].split("|")[2:]
        assert {p["x"] for p in wall0["polygon"]} == {p["x"] for p in wall1["polygon"]}
        assert {p["z"] for p in wall0["polygon"]} == {p["z"] for p in wall1["polygon"]}
        lo, hi = door["holePolygon"]
        assert 0.0 <= lo["x"] < hi["x"] <= _wall_length(wall0) + 1e-9
        assert lo["x"] <= door["assetPosition"]["x"] <= hi["x"]
    names = house["metadata"]["emrd"]["rooms"]
    by_name = {name: rooms[rid] for rid, name in names.items()}
    ids = IdTable.from_house(house)
    for obj in house["objects"]:
        ours = next(o for o in layout.objects if o.object_id == ids.emrd(obj["id"]))
        polygon = by_name[ours.room]["floorPolygon"]
        assert _inside(polygon, obj["position"]["x"], obj["position"]["z"]), obj["id"]
    thor_ids = [o["id"] for o in house["objects"]] + [d["id"] for d in house["doors"]]
    assert len(set(thor_ids)) == len(thor_ids)
    assert sorted(ids.to_emrd.values()) == sorted(o.object_id for o in layout.objects)
    json.dumps(house)


@pytest.mark.parametrize("condition", ["baseline", "low_light", "texture"])
def test_small_layout_builds_a_well_formed_house(layout: Layout, condition: str) -> None:
    check_well_formed(build_house(layout, condition, 1), layout)


@settings(max_examples=25)
@given(seed=st.integers(0, 2**32 - 1), condition=st.sampled_from(["baseline", "texture"]))
def test_every_generated_office_builds_a_well_formed_house(seed: int, condition: str) -> None:
    layout = generate_layout(seed)
    check_well_formed(build_house(layout, condition, seed), layout)


def test_rooms_keep_our_names_and_map_to_thor_room_types(layout: Layout) -> None:
    house = build_house(layout, "baseline", 0)
    names = house["metadata"]["emrd"]["rooms"]
    types = {names[r["id"]]: r["roomType"] for r in house["rooms"]}
    assert types == {
        "Office": "LivingRoom",
        "Conference Room": "LivingRoom",
        "Kitchen": "Kitchen",
        "Entrance": "LivingRoom",
    }


def test_doorway_is_a_hole_in_the_wall_both_rooms_share(layout: Layout) -> None:
    house = build_house(layout, "baseline", 0)
    door = next(d for d in house["doors"] if d["id"] == "door|1|2")  # Office-Conference
    assert (door["wall0"], door["wall1"]) == (
        "wall|1|4.00|4.00|4.00|8.00",
        "wall|2|4.00|4.00|4.00|8.00",
    )
    # Office east wall runs south from (4, 8): the gap centred at z=6 spans 1.5..2.5.
    assert [p["x"] for p in door["holePolygon"]] == [1.5, 2.5]
    assert door["openness"] == 1.0


def test_exit_is_a_closed_door_in_an_outside_wall(layout: Layout) -> None:
    house = build_house(layout, "baseline", 0)
    exit_door = next(d for d in house["doors"] if d["id"].startswith("door|exterior"))
    assert exit_door["room0"] == exit_door["room1"] == "room|4"
    assert exit_door["wall1"] == "wall|exterior|9.00|0.00|9.00|4.00"
    assert exit_door["openable"] is False
    assert IdTable.from_house(house).emrd(exit_door["id"]) == "Door_1"


@pytest.mark.parametrize("seed", [3, 11])
def test_objects_are_centred_on_their_support_height(seed: int) -> None:
    """``y = elevation + height / 2``: items on desks and counters sit on their tops."""
    layout = generate_layout(seed)
    house = build_house(layout, "baseline", seed)
    ours = {o.object_id: o for o in layout.objects}
    ids = IdTable.from_house(house)
    for placed in house["objects"]:
        obj = ours[ids.emrd(placed["id"]) or ""]
        assert placed["position"]["y"] == pytest.approx(obj.elevation + obj.height / 2, abs=1e-4)
    assert any(o.elevation > 0 for o in layout.objects), "no item on a desk or counter"


def test_a_laptop_stands_on_the_desk_top_and_carries_its_asset() -> None:
    layout = generate_layout(3)
    house = build_house(layout, "baseline", 3)
    ids = IdTable.from_house(house)
    laptop = next(o for o in house["objects"] if ids.emrd(o["id"]) == "Laptop_1")
    obj = next(o for o in layout.objects if o.object_id == "Laptop_1")
    assert obj.elevation > 0.7 and laptop["position"]["y"] > obj.elevation
    assert laptop["assetId"] == "Laptop_1" and laptop["kinematic"] is True


def test_low_light_dims_every_light_by_the_condition_factor(layout: Layout) -> None:
    base = build_house(layout, "baseline", 0)["proceduralParameters"]["lights"]
    dark = build_house(layout, "low_light", 0)["proceduralParameters"]["lights"]
    factor = condition_params("low_light").light_factor
    assert [d["intensity"] for d in dark] == [pytest.approx(b["intensity"] * factor) for b in base]


def test_texture_colours_are_seeded(layout: Layout) -> None:
    def colours(condition: str, seed: int) -> list[Any]:
        house = build_house(layout, condition, seed)
        return [w["material"]["color"] for w in house["walls"]]

    assert colours("texture", 1) == colours("texture", 1)
    assert colours("texture", 1) != colours("texture", 2)
    assert colours("baseline", 1) == colours("baseline", 2)
    assert colours("texture", 1) != colours("baseline", 1)


def test_same_inputs_give_the_same_house(layout: Layout) -> None:
    assert build_house(layout, "texture", 5) == build_house(layout, "texture", 5)


def test_agent_pose_goes_into_metadata(layout: Layout) -> None:
    from pytest_emrd.world._model import WorldPose

    house = build_house(layout, "baseline", 0, agent=WorldPose(2.0, 5.0, 270.0))
    agent = house["metadata"]["agent"]
    assert (agent["position"]["x"], agent["position"]["z"], agent["rotation"]["y"]) == (
        2.0,
        5.0,
        270.0,
    )


def test_asset_override_wins_over_the_vendored_table(layout: Layout) -> None:
    house = build_house(layout, "baseline", 0, asset_ids={"Desk": "Desk_207_1"})
    ids = IdTable.from_house(house)
    desk = next(o for o in house["objects"] if ids.emrd(o["id"]) == "Desk_1")
    assert desk["assetId"] == "Desk_207_1"


def _off_wall(layout: Layout) -> Layout:
    moved = replace(layout.doorways[0], x=3.0)  # Office-Conference gap moved into the room
    return replace(layout, doorways=(moved, *layout.doorways[1:]))


def _too_wide(layout: Layout) -> Layout:
    wide = Doorway("Doorway_1", "Office", "Conference Room", 4.0, 4.3, 1.0, "z")
    return replace(layout, doorways=(wide, *layout.doorways[1:]))


def _unknown_type(layout: Layout) -> Layout:
    odd = replace(layout.objects[-1], object_type="Piano")
    return replace(layout, objects=(*layout.objects[:-1], odd))


@pytest.mark.parametrize(
    ("make", "condition", "message"),
    [
        (lambda lay: lay, "smoke", "condition='smoke'"),
        (_off_wall, "baseline", "not on a wall shared by"),
        (_too_wide, "baseline", "does not fit on wall"),
        (_unknown_type, "baseline", "object_type='Piano'.*asset_ids="),
    ],
    ids=["unknown-condition", "doorway-off-the-wall", "doorway-past-wall-end", "unmapped-type"],
)
def test_bad_input_is_a_config_error(
    layout: Layout, make: Any, condition: str, message: str
) -> None:
    with pytest.raises(ConfigError, match=message):
        build_house(make(layout), condition, 0)
