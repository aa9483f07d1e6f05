"""The ProcTHOR house: well formed, faithful to the layout, deterministic."""

from __future__ import annotations

import json
import math
from dataclasses import replace
from pathlib import Path
from typing import Any

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pytest_emrd.errors import ConfigError
from pytest_emrd.trajectory import CONDITIONS
from pytest_emrd.world import (
    PAPER_OFFICE_SEED,
    Doorway,
    Layout,
    WorldPose,
    condition_params,
    generate_layout,
)
from pytest_emrd.world.thor import SCHEMA, IdTable, assets, build_house, choose_asset


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


DB = json.loads((Path(__file__).parent / "data" / "asset_database.json").read_text())["assets"]
"""The vendored ProcTHOR asset database: assetId -> [objectType, box x, box y, box z]."""


def _footprint(placed: dict[str, Any]) -> tuple[float, float, float, float]:
    _, bx, _, bz = DB[placed["assetId"]]
    if round(placed["rotation"]["y"]) % 180 == 90:
        bx, bz = bz, bx
    x, z = placed["position"]["x"], placed["position"]["z"]
    return (x - bx / 2, z - bz / 2, x + bx / 2, z + bz / 2)


def check_geometry(house: dict[str, Any], layout: Layout) -> None:
    """Each asset's box stands on the floor or on the top of the asset it stands on, and
    its footprint stays inside its room (walls are ``wall_thickness`` thick)."""
    ids = IdTable.from_house(house)
    ours = {o.object_id: o for o in layout.objects}
    tops = []
    for placed in house["objects"]:
        _, _, height, _ = DB[placed["assetId"]]
        tops.append((placed, placed["position"]["y"] + height / 2))
    half = layout.wall_thickness / 2
    for placed in house["objects"]:
        obj = ours[ids.emrd(placed["id"]) or ""]
        object_type, _, height, _ = DB[placed["assetId"]]
        assert object_type == obj.object_type, placed
        bottom = placed["position"]["y"] - height / 2
        x0, z0, x1, z1 = _footprint(placed)
        room = layout.room(obj.room)
        assert room.x0 + half - 1e-4 <= x0 and x1 <= room.x1 - half + 1e-4, placed["id"]
        assert room.z0 + half - 1e-4 <= z0 and z1 <= room.z1 - half + 1e-4, placed["id"]
        if obj.elevation == 0:
            assert bottom == pytest.approx(0.0, abs=1e-3), placed["id"]
            continue
        x, z = placed["position"]["x"], placed["position"]["z"]
        supports = [
            top
            for other, top in tops
            if other is not placed
            and _footprint(other)[0] <= x <= _footprint(other)[2]
            and _footprint(other)[1] <= z <= _footprint(other)[3]
        ]
        assert any(top == pytest.approx(bottom, abs=1e-3) for top in supports), placed["id"]


def test_every_vendored_asset_is_in_the_procthor_database() -> None:
    """Every id the adapter can emit exists in ProcTHOR's database with that type and box."""
    for asset_id, asset in assets().items():
        object_type, bx, by, bz = DB[asset_id]
        assert object_type == asset.object_type
        assert (asset.width, asset.height, asset.depth) == (bx, by, bz)


@pytest.mark.parametrize("seed", [*range(100), PAPER_OFFICE_SEED])
def test_assets_exist_stand_on_their_support_and_stay_in_their_room(seed: int) -> None:
    layout = generate_layout(seed)
    house = build_house(layout, "baseline", seed)
    emitted = [o["assetId"] for o in house["objects"]] + [d["assetId"] for d in house["doors"]]
    assert set(emitted) <= set(DB)
    check_geometry(house, layout)


def test_a_laptop_stands_on_its_desk_and_a_sink_on_its_counter() -> None:
    layout = generate_layout(3)
    house = build_house(layout, "baseline", 3)
    ids = IdTable.from_house(house)
    placed = {ids.emrd(o["id"]): o for o in house["objects"]}

    def top(oid: str) -> float:
        return placed[oid]["position"]["y"] + DB[placed[oid]["assetId"]][2] / 2

    def bottom(oid: str) -> float:
        return placed[oid]["position"]["y"] - DB[placed[oid]["assetId"]][2] / 2

    assert bottom("Laptop_1") == pytest.approx(top("Desk_1"), abs=1e-3)
    assert bottom("Sink_1") == pytest.approx(top("CounterTop_1"), abs=1e-3)
    assert placed["Laptop_1"]["kinematic"] is True


def test_each_object_gets_the_asset_closest_to_its_size() -> None:
    """The conference table is a long table, not a square one (EMRD: 2.6-3.2 x 1.1 m)."""
    layout = generate_layout(3)
    table = next(o for o in layout.objects if o.object_type == "DiningTable")
    chosen = choose_asset("DiningTable", table.width, table.depth, table.height)
    assert chosen.width > 2.0 and chosen.depth < 1.3
    assert chosen == min(
        (a for a in assets().values() if a.object_type == "DiningTable"),
        key=lambda a: (
            sum(
                2 * (have - want) if have > want else want - have
                for have, want in (
                    (a.width, table.width),
                    (a.depth, table.depth),
                    (a.height, table.height),
                )
            ),
            a.asset_id,
        ),
    )


def test_low_light_dims_every_light_by_the_condition_factor(layout: Layout) -> None:
    base = build_house(layout, "baseline", 0)["proceduralParameters"]["lights"]
    dark = build_house(layout, "low_light", 0)["proceduralParameters"]["lights"]
    factor = condition_params("low_light").light_factor
    assert [d["intensity"] for d in dark] == [pytest.approx(b["intensity"] * factor) for b in base]


def test_low_light_also_dims_the_sky_thor_takes_ambient_light_from(layout: Layout) -> None:
    sky = {c: build_house(layout, c, 0)["proceduralParameters"]["skyboxId"] for c in CONDITIONS}
    assert sky["low_light"] == "Sky2Dusk" != sky["baseline"] == sky["texture"] == "Sky1"


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


def test_the_start_goes_into_agent_poses_on_the_grid(layout: Layout) -> None:
    """``CreateHouse`` reads ``metadata.agentPoses[agentMode]`` only; its x and z are on
    THOR's 0.25 m grid, so the reachable lattice THOR walks from it is the grid itself."""
    house = build_house(layout, "baseline", 0, agent=WorldPose(2.07, 5.1, 270.0))
    pose = house["metadata"]["agentPoses"]["default"]
    assert (pose["position"]["x"], pose["position"]["z"], pose["rotation"]["y"]) == (
        2.0,
        5.0,
        270.0,
    )
    assert (pose["horizon"], pose["standing"]) == (0, True)
    other = build_house(layout, "baseline", 0, agent=WorldPose(2.0, 5.0, 0.0), agent_mode="arm")
    assert set(other["metadata"]["agentPoses"]) == {"arm"}


def test_a_start_inside_furniture_moves_to_the_nearest_free_grid_point(layout: Layout) -> None:
    desk = next(o for o in layout.objects if o.object_id == "Desk_1")
    house = build_house(layout, "baseline", 0, agent=WorldPose(desk.x, desk.z, 0.0))
    pose = house["metadata"]["agentPoses"]["default"]["position"]
    desk_box = next(o for o in house["objects"] if o["id"].startswith("Desk|"))
    x0, z0, x1, z1 = _footprint(desk_box)
    gap = math.hypot(max(x0 - pose["x"], 0, pose["x"] - x1), max(z0 - pose["z"], 0, pose["z"] - z1))
    assert gap >= 0.3 and pose["x"] % 0.25 == 0 and pose["z"] % 0.25 == 0


def test_asset_override_wins_over_the_vendored_table(layout: Layout) -> None:
    house = build_house(layout, "baseline", 0, asset_ids={"Desk": "Desk_204_1"})
    ids = IdTable.from_house(house)
    desk = next(o for o in house["objects"] if ids.emrd(o["id"]) == "Desk_1")
    assert desk["assetId"] == "Desk_204_1"


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
        (_unknown_type, "baseline", "object_type='Piano' has no ProcTHOR asset"),
    ],
    ids=["unknown-condition", "doorway-off-the-wall", "doorway-past-wall-end", "unmapped-type"],
)
def test_bad_input_is_a_config_error(
    layout: Layout, make: Any, condition: str, message: str
) -> None:
    with pytest.raises(ConfigError, match=message):
        build_house(make(layout), condition, 0)


@pytest.mark.parametrize(
    "asset_ids",
    [{"CoffeeMachine": "Coffee_Machine_1"}, {"Stool": "Stool_1"}, {"Desk": "Desk_207_1"}],
    ids=["coffee-machine", "stool", "desk"],
)
def test_an_asset_id_thor_would_skip_is_refused_at_build_time(
    layout: Layout, asset_ids: dict[str, str]
) -> None:
    """THOR skips an unknown ``assetId`` silently; the house builder refuses it instead."""
    ((object_type, asset_id),) = asset_ids.items()
    with pytest.raises(ConfigError, match=f"names no {object_type} in the ProcTHOR asset"):
        build_house(layout, "baseline", 0, asset_ids=asset_ids)
    assert asset_id not in DB
