"""Layout generation: determinism, contents, and the no-overlap / inside-room properties."""

from __future__ import annotations

import json
from collections import Counter

import numpy as np
from hypothesis import given
from hypothesis import strategies as st

from pytest_emrd._serde import from_dict, to_dict
from pytest_emrd.rooms import CONFERENCE, ENTRANCE, KITCHEN, OFFICE, ROOM_NAMES
from pytest_emrd.world import CATEGORY_OF, Layout, footprint, generate_layout, paper_office
from pytest_emrd.world._geometry import rects_overlap

seeds = st.integers(min_value=0, max_value=2**32 - 1)


def test_same_seed_same_layout_bit_for_bit() -> None:
    a, b = generate_layout(123), generate_layout(123)
    assert a == b
    assert json.dumps(to_dict(a)) == json.dumps(to_dict(b))
    assert generate_layout(124) != a


def test_layout_round_trips_through_json(office: Layout) -> None:
    assert from_dict(Layout, json.loads(json.dumps(to_dict(office)))) == office


def test_rooms_form_the_two_by_two_office(office: Layout) -> None:
    rooms = {r.name: r for r in office.rooms}
    assert tuple(rooms) == ROOM_NAMES
    assert rooms[OFFICE].x0 == 0 and rooms[OFFICE].z1 == office.depth  # top-left
    assert rooms[CONFERENCE].x1 == office.width and rooms[CONFERENCE].z0 == rooms[OFFICE].z0
    assert rooms[KITCHEN].x0 == 0 and rooms[KITCHEN].z0 == 0  # bottom-left
    assert rooms[ENTRANCE].x1 == office.width and rooms[ENTRANCE].z0 == 0
    assert 10 <= office.width <= 14 and 9 <= office.depth <= 12


def test_worked_example_seed_7_contents(office: Layout) -> None:
    inv = office.inventory()
    assert inv[CONFERENCE] == {"DiningTable": 1, "Chair": 8, "Television": 1}
    assert inv[KITCHEN] == {
        "Fridge": 1,
        "CounterTop": 2,
        "Sink": 1,
        "CoffeeMachine": 1,
        "Microwave": 1,
        "Stool": 1,
    }
    assert inv[ENTRANCE] == {"Door": 1, "Desk": 1, "ArmChair": 2, "HousePlant": 1}
    assert inv[OFFICE] == {"ShelvingUnit": 1, "Desk": 3, "Chair": 3, "Laptop": 3, "HousePlant": 2}
    assert [(d.object_id, d.room_a, d.room_b) for d in office.doorways] == [
        ("Doorway_1", OFFICE, CONFERENCE),
        ("Doorway_2", OFFICE, KITCHEN),
        ("Doorway_3", CONFERENCE, ENTRANCE),
        ("Doorway_4", KITCHEN, ENTRANCE),
    ]


@given(seeds)
def test_ids_are_type_n_unique_and_categorised(seed: int) -> None:
    layout = generate_layout(seed)
    ids = [o.object_id for o in layout.objects]
    assert len(ids) == len(set(ids))
    by_type: dict[str, list[int]] = {}
    for o in layout.objects:
        kind, _, n = o.object_id.rpartition("_")
        assert kind == o.object_type
        by_type.setdefault(kind, []).append(int(n))
        assert o.category == CATEGORY_OF[o.object_type]
    for numbers in by_type.values():
        assert sorted(numbers) == list(range(1, len(numbers) + 1))
    assert 32 <= len(layout.objects) <= 45  # 35-45 typically; a crowded seed may drop an item
    conference = layout.inventory()[CONFERENCE]
    assert conference["DiningTable"] == 1 and conference["Chair"] == 8
    assert Counter(o.object_type for o in layout.objects)["Door"] == 1


@given(seeds)
def test_floor_furniture_never_overlaps_and_stays_in_its_room(seed: int) -> None:
    layout = generate_layout(seed)
    floor = [o for o in layout.objects if o.elevation == 0 and o.object_type != "Doorway"]
    rects = np.array([footprint(o) for o in floor])
    overlap = rects_overlap(rects, rects)
    np.fill_diagonal(overlap, False)
    assert not overlap.any()
    for o in layout.objects:
        if o.object_type == "Doorway":
            continue
        room = layout.room(o.room)
        x0, z0, x1, z1 = footprint(o)
        assert room.x0 <= x0 and x1 <= room.x1 and room.z0 <= z0 and z1 <= room.z1, o


@given(seeds)
def test_items_stand_on_furniture_and_doorways_sit_on_shared_walls(seed: int) -> None:
    layout = generate_layout(seed)
    floor = [o for o in layout.objects if o.elevation == 0]
    for item in (o for o in layout.objects if o.elevation > 0):
        x0, z0, x1, z1 = footprint(item)
        assert any(
            f.height == item.elevation
            and f.room == item.room
            and (fp := footprint(f))[0] <= x0
            and x1 <= fp[2]
            and fp[1] <= z0
            and z1 <= fp[3]
            for f in floor
        ), item
    for d in layout.doorways:
        a, b = layout.room(d.room_a), layout.room(d.room_b)
        assert a.contains(d.x, d.z) and b.contains(d.x, d.z)
        half = d.width / 2
        lo, hi = (d.x - half, d.x + half) if d.axis == "x" else (d.z - half, d.z + half)
        shared = (
            (max(a.x0, b.x0), min(a.x1, b.x1))
            if d.axis == "x"
            else (max(a.z0, b.z0), min(a.z1, b.z1))
        )
        assert shared[0] < lo and hi < shared[1]


@given(seeds)
def test_every_room_has_two_doorways_to_adjacent_rooms(seed: int) -> None:
    """B3's suffix ("2 doorways connecting to adjacent rooms") holds in every layout."""
    layout = generate_layout(seed)
    per_room = Counter(r for d in layout.doorways for r in (d.room_a, d.room_b))
    assert per_room == {room: 2 for room in ROOM_NAMES}


def test_paper_office_holds_the_full_furniture_recipe() -> None:
    office = paper_office()
    assert office is paper_office()  # built once
    assert office.inventory() == {
        OFFICE: {"ShelvingUnit": 2, "Desk": 4, "Chair": 4, "Laptop": 3, "HousePlant": 2},
        CONFERENCE: {"DiningTable": 1, "Chair": 8, "Television": 1},
        KITCHEN: {
            "Fridge": 1, "CounterTop": 2, "Sink": 1, "CoffeeMachine": 1, "Microwave": 1, "Stool": 1
        },
        ENTRANCE: {"Door": 1, "Desk": 1, "ArmChair": 2, "HousePlant": 1},
    }  # fmt: skip
    table = next(o for o in office.objects if o.object_type == "DiningTable")
    assert table.width == 3.2 and len(office.doorways) == 4
