"""The seeded procedural office (ProcTHOR-style): rooms, doorways, exit, furniture.

Four rooms in a 2x2 arrangement (world frame: ``x`` east, ``z`` north): Office top-left,
Conference Room top-right, Kitchen bottom-left, Entrance bottom-right. Per seed:

* the top row is 4.8-6.2 m deep and the bottom row 4.2-5.6 m, so the building is
  9-11.8 m deep; the Office is 5.2-7.0 m wide and the Conference Room 5.5-7.0 m, so the
  building is 10.7-14 m wide; the Kitchen is 4.2-6.0 m wide and the Entrance takes the
  rest (at least 4.7 m). All dimensions are on a 10 cm grid, every position on 1 cm.
* a 1 m doorway joins each adjacent pair (Office-Conference, Office-Kitchen,
  Conference-Entrance, Kitchen-Entrance) at a random point of the shared wall, at least
  0.9 m from any corner. The four doorways form a cycle, so every room has exactly two
  doorways to adjacent rooms in every layout: the B3 prompt suffix ("2 doorways connecting
  to adjacent rooms") is true of every office this module builds.
* the building exit ``Door_1`` sits on the Entrance's south or east outer wall.
* furniture follows :mod:`pytest_emrd.world._furnish`.

Ids are ``Type_N``, numbered per ``objectType`` across the layout in the order doorways,
exit, then Office, Conference Room, Kitchen, Entrance. Generation draws only from
:class:`~pytest_emrd.world._rng.StableRng`, so a seed gives the same layout bit for bit
on every machine and Python/numpy version.
"""

from __future__ import annotations

from collections import Counter

from pytest_emrd.rooms import CONFERENCE, ENTRANCE, KITCHEN, OFFICE
from pytest_emrd.world._catalog import KINDS
from pytest_emrd.world._furnish import furnish
from pytest_emrd.world._geometry import rect_at
from pytest_emrd.world._model import Doorway, Layout, Room, WorldObject
from pytest_emrd.world._planner import Placed, Planner
from pytest_emrd.world._rng import StableRng

DOOR_WIDTH = 1.0
CORNER_CLEARANCE = 0.9
"""Minimum distance between a doorway's centre and the end of its wall."""
APPROACH_DEPTH = 1.3
"""Depth of the walkable zone kept free on each side of a doorway and before the exit."""
PAIRS = ((OFFICE, CONFERENCE), (OFFICE, KITCHEN), (CONFERENCE, ENTRANCE), (KITCHEN, ENTRANCE))


def _dim(rng: StableRng, low: float, high: float) -> float:
    return round(rng.uniform(low, high), 1)


def generate_layout(seed: int) -> Layout:
    """The office for ``seed``: deterministic, bit for bit."""
    rng = StableRng(seed)
    top, bottom = _dim(rng, 4.8, 6.2), _dim(rng, 4.2, 5.6)
    w_office, w_conf = _dim(rng, 5.2, 7.0), _dim(rng, 5.5, 7.0)
    width = round(w_office + w_conf, 1)
    w_kitchen = _dim(rng, 4.2, min(6.0, width - 4.7))
    depth = round(top + bottom, 1)
    rooms = {
        OFFICE: Room(OFFICE, 0.0, bottom, w_office, depth),
        CONFERENCE: Room(CONFERENCE, w_office, bottom, width, depth),
        KITCHEN: Room(KITCHEN, 0.0, 0.0, w_kitchen, bottom),
        ENTRANCE: Room(ENTRANCE, w_kitchen, 0.0, width, bottom),
    }
    doorways = _doorways(rng, rooms)
    planner = Planner(rng)
    for d in doorways:
        planner.reserve(rect_at(d.x, d.z, DOOR_WIDTH + 0.4, 2 * APPROACH_DEPTH, _rot(d.axis)))
    exit_door = _exit(rng, rooms[ENTRANCE])
    planner.reserve(
        rect_at(exit_door.x, exit_door.z, DOOR_WIDTH + 0.4, 2 * APPROACH_DEPTH, exit_door.rotation)
    )
    furnish(planner, rooms)
    objects = [*_doorway_objects(doorways), exit_door, *_number(planner.placed)]
    return Layout(
        seed=seed,
        width=width,
        depth=depth,
        rooms=tuple(rooms[name] for name in (OFFICE, CONFERENCE, KITCHEN, ENTRANCE)),
        doorways=doorways,
        objects=tuple(objects),
    )


def _rot(axis: str) -> float:
    return 0.0 if axis == "x" else 90.0


def _doorways(rng: StableRng, rooms: dict[str, Room]) -> tuple[Doorway, ...]:
    out = []
    for i, (a, b) in enumerate(PAIRS, start=1):
        ra, rb = rooms[a], rooms[b]
        if ra.z0 == rb.z0:  # side by side: the wall runs along z at the shared x
            lo, hi = max(ra.z0, rb.z0), min(ra.z1, rb.z1)
            x = ra.x1 if ra.x1 == rb.x0 else ra.x0
            z = round(rng.uniform(lo + CORNER_CLEARANCE, hi - CORNER_CLEARANCE), 2)
            out.append(Doorway(f"Doorway_{i}", a, b, x, z, DOOR_WIDTH, "z"))
        else:  # stacked: the wall runs along x at the shared z
            lo, hi = max(ra.x0, rb.x0), min(ra.x1, rb.x1)
            z = ra.z0 if ra.z0 == rb.z1 else ra.z1
            x = round(rng.uniform(lo + CORNER_CLEARANCE, hi - CORNER_CLEARANCE), 2)
            out.append(Doorway(f"Doorway_{i}", a, b, x, z, DOOR_WIDTH, "x"))
    return tuple(out)


def _doorway_objects(doorways: tuple[Doorway, ...]) -> list[WorldObject]:
    kind = KINDS["Doorway"]
    return [
        WorldObject(
            object_id=d.object_id,
            object_type=kind.object_type,
            room=d.room_a,
            category=kind.category,
            x=d.x,
            z=d.z,
            width=d.width,
            depth=kind.depth,
            height=kind.height,
            rotation=_rot(d.axis),
            color=kind.main_color,
        )
        for d in doorways
    ]


def _exit(rng: StableRng, room: Room) -> WorldObject:
    kind = KINDS["Door"]
    inset = kind.depth / 2
    if rng.random() < 0.5:  # south wall, facing north into the room
        x = round(rng.uniform(room.x0 + CORNER_CLEARANCE, room.x1 - CORNER_CLEARANCE), 2)
        z, rotation = room.z0 + inset, 0.0
    else:  # east wall, facing west
        z = round(rng.uniform(room.z0 + CORNER_CLEARANCE, room.z1 - CORNER_CLEARANCE), 2)
        x, rotation = room.x1 - inset, 270.0
    return WorldObject(
        object_id="Door_1",
        object_type=kind.object_type,
        room=room.name,
        category=kind.category,
        x=x,
        z=z,
        width=DOOR_WIDTH,
        depth=kind.depth,
        height=kind.height,
        rotation=rotation,
        color=kind.main_color,
    )


def _number(placed: list[Placed]) -> list[WorldObject]:
    counts: Counter[str] = Counter({"Doorway": 0, "Door": 1})
    out = []
    for p in placed:
        kind = KINDS[p.kind]
        counts[kind.object_type] += 1
        out.append(
            WorldObject(
                object_id=f"{kind.object_type}_{counts[kind.object_type]}",
                object_type=kind.object_type,
                room=p.room,
                category=kind.category,
                x=p.x,
                z=p.z,
                width=p.width,
                depth=kind.depth,
                height=kind.height,
                rotation=p.rotation,
                color=kind.main_color,
                elevation=kind.elevation,
            )
        )
    return out
