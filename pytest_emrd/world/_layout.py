"""The seeded procedural office (ProcTHOR-style): rooms, doorways, exit, furniture.

Four rooms in a 2x2 arrangement: Office top-left, Conference Room top-right, Kitchen
bottom-left, Entrance bottom-right, sizes drawn per seed on a 10 cm grid (positions on
1 cm). A 1 m doorway joins each adjacent pair at a random point of the shared wall, at
least 0.9 m from any corner: the four doorways form a cycle, so every room has exactly two
(the B3 prompt suffix is true of every office). The exit ``Door_1`` sits on the Entrance's
south or east outer wall. Furniture, big items first (an item that finds no free spot is
left out), is each room's recipe (:func:`_office` ... :func:`_entrance`). Ids are ``Type_N``,
numbered per ``objectType`` in the order doorways, exit, Office, Conference Room, Kitchen,
Entrance. Generation draws only from :class:`~pytest_emrd.world._rng.StableRng`: a seed
gives the same layout bit for bit.

Furniture is placed in *units*, groups of objects placed together (a desk with its chair
and laptop) in their own frame: ``u`` metres to the right, ``v`` forward (the front faces
the room). The :class:`Planner` accepts a candidate placement when its footprint overlaps
neither a ``solid`` floor footprint nor a ``clear`` zone (doorway approaches, each unit's
access zone), and its access zone overlaps no solid footprint and lies inside the room.
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from pytest_emrd.rooms import CONFERENCE, ENTRANCE, KITCHEN, OFFICE
from pytest_emrd.world._catalog import KINDS
from pytest_emrd.world._geometry import (
    HEADINGS,
    Rect,
    footprint,
    local_to_world,
    rect_at,
    rects_at,
    rects_overlap,
)
from pytest_emrd.world._geometry import unit as unit_vector
from pytest_emrd.world._model import Doorway, Layout, Room, WorldObject
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
    """The office for ``seed``: deterministic, bit for bit.

    :param seed: Any integer.
    :returns: The generated :class:`Layout`.
    """
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
    landmarks = [
        _object("Doorway", d.object_id, d.room_a, d.x, d.z, d.width, 0.0 if d.axis == "x" else 90.0)
        for d in doorways
    ]
    landmarks.append(_exit(rng, rooms[ENTRANCE]))
    planner = Planner(rng)
    approach = (DOOR_WIDTH + 0.4, 2 * APPROACH_DEPTH)  # kept walkable before every door
    planner.clear += [rect_at(o.x, o.z, *approach, o.rotation) for o in landmarks]
    _office(planner, rooms[OFFICE])
    _conference(planner, rooms[CONFERENCE])
    _kitchen(planner, rooms[KITCHEN])
    _entrance(planner, rooms[ENTRANCE])
    return Layout(
        seed=seed,
        width=width,
        depth=depth,
        rooms=tuple(rooms.values()),
        doorways=doorways,
        objects=(*landmarks, *planner.placed),
    )


def _along(rng: StableRng, lo: float, hi: float) -> float:
    """A point of the wall from ``lo`` to ``hi``, :data:`CORNER_CLEARANCE` clear of its ends."""
    return round(rng.uniform(lo + CORNER_CLEARANCE, hi - CORNER_CLEARANCE), 2)


def _doorways(rng: StableRng, rooms: dict[str, Room]) -> tuple[Doorway, ...]:
    out = []
    for i, (a, b) in enumerate(PAIRS, start=1):
        ra, rb = rooms[a], rooms[b]
        if ra.z0 == rb.z0:  # side by side: the wall runs along z at the shared x
            x = ra.x1 if ra.x1 == rb.x0 else ra.x0
            z, axis = _along(rng, max(ra.z0, rb.z0), min(ra.z1, rb.z1)), "z"
        else:  # stacked: the wall runs along x at the shared z
            z = ra.z0 if ra.z0 == rb.z1 else ra.z1
            x, axis = _along(rng, max(ra.x0, rb.x0), min(ra.x1, rb.x1)), "x"
        out.append(Doorway(f"Doorway_{i}", a, b, x, z, DOOR_WIDTH, axis))
    return tuple(out)


def _object(
    kind_name: str, object_id: str, room: str, x: float, z: float, width: float, rotation: float
) -> WorldObject:
    kind = KINDS[kind_name]
    return WorldObject(
        object_id=object_id,
        object_type=kind.object_type,
        room=room,
        category=kind.category,
        x=x,
        z=z,
        width=width,
        depth=kind.depth,
        height=kind.height,
        rotation=rotation,
        color=next(iter(kind.colors.values())),
        elevation=kind.elevation,
    )


def _exit(rng: StableRng, room: Room) -> WorldObject:
    inset = KINDS["Door"].depth / 2
    if rng.random() < 0.5:  # south wall, facing north into the room
        x, z, rotation = _along(rng, room.x0, room.x1), room.z0 + inset, 0.0
    else:  # east wall, facing west
        x, z, rotation = room.x1 - inset, _along(rng, room.z0, room.z1), 270.0
    return _object("Door", "Door_1", room.name, x, z, DOOR_WIDTH, rotation)


TABLE_LENGTHS = (3.2, 3.04, 2.8, 2.64)
"""Conference table lengths tried, longest first (multiples of 0.08 m: chair slots stay on
the centimetre grid)."""
COUNTER_LENGTHS = (1.6, 1.8, 2.0, 2.2)


def _single(kind: str, access: float, *, around: bool = False) -> Unit:
    k = KINDS[kind]
    return Unit((Member(kind),), k.width, k.depth, access, around)


def _desk_unit(with_laptop: bool, laptop_u: float) -> Unit:
    desk, chair = KINDS["Desk"], KINDS["Chair"]
    depth = desk.depth + 0.05 + chair.depth
    desk_v = -depth / 2 + desk.depth / 2
    members = [Member("Desk", v=desk_v), Member("Chair", v=depth / 2 - chair.depth / 2, turn=180.0)]
    if with_laptop:
        members.append(Member("Laptop", u=laptop_u, v=round(desk_v + 0.1, 2)))
    return Unit(tuple(members), desk.width, round(depth, 2), 0.7)


def _office(p: Planner, room: Room) -> None:
    rng = p.rng
    for _ in range(rng.integer(1, 2)):
        p.against_wall(room, _single("ShelvingUnit", 0.8))
    n_desks = rng.integer(3, 4)
    n_laptops = min(rng.integer(2, 3), n_desks)
    laptops = set(rng.shuffled(range(n_desks))[:n_laptops])
    for i in range(n_desks):
        laptop_u = round(rng.uniform(-0.4, 0.4), 2)
        p.against_wall(room, _desk_unit(i in laptops, laptop_u))
    for _ in range(2):
        p.against_wall(room, _single("HousePlant", 0.5))


def _table_unit(length: float) -> Unit:
    table, chair = KINDS["DiningTable"], KINDS["Chair"]
    offset = table.depth / 2 + 0.05 + chair.depth / 2
    chairs = [
        Member("Chair", u=round(-length / 2 + length / 8 + i * length / 4, 2), v=side, turn=turn)
        for side, turn in ((offset, 180.0), (-offset, 0.0))
        for i in range(4)
    ]
    return Unit(
        (Member("DiningTable", width=length), *chairs),
        length,
        round(2 * offset + chair.depth, 2),
        0.75,
        around=True,
    )


def _conference(p: Planner, room: Room) -> None:
    along_x = (room.x1 - room.x0) >= (room.z1 - room.z0)
    rotations = (0.0, 180.0) if along_x else (90.0, 270.0)
    for length in TABLE_LENGTHS:
        if p.free(room, _table_unit(length), rotations, spread=0.6):
            break
    p.against_wall(room, _single("Television", 1.0), "EW" if along_x else "NS")


def _counter_unit(length: float, items: tuple[Member, ...]) -> Unit:
    counter = KINDS["CounterTop"]
    return Unit((Member("CounterTop", width=length), *items), length, counter.depth, 0.9)


def _kitchen(p: Planner, room: Room) -> None:
    rng = p.rng
    p.against_wall(room, _single("Fridge", 0.9))
    length = rng.choice(COUNTER_LENGTHS)
    sink_side = rng.choice((-1.0, 1.0))
    items = (
        Member("Sink", u=sink_side * length / 4),
        Member("CoffeeMachine", u=-sink_side * length / 4, v=0.1),
    )
    p.against_wall(room, _counter_unit(length, items))
    length = rng.choice(COUNTER_LENGTHS)
    micro_u = round(rng.uniform(-(length / 2 - 0.4), length / 2 - 0.4), 2)
    p.against_wall(room, _counter_unit(length, (Member("Microwave", u=micro_u, v=0.05),)))
    p.free(room, _single("Stool", 0.45, around=True), HEADINGS)


def _entrance(p: Planner, room: Room) -> None:
    p.against_wall(room, _single("ReceptionDesk", 1.0))
    for _ in range(2):
        p.against_wall(room, _single("ArmChair", 0.7))
    p.against_wall(room, _single("HousePlant", 0.5))


WALL_GAP = 0.02
"""Distance between a wall and the back of furniture standing against it."""
CANDIDATES = 96
"""Placements tried per unit before it is given up (in batches of :data:`BATCH`)."""
BATCH = 8
#: Wall side -> rotation that makes a unit standing against it face into the room.
SIDE_ROTATION = {"N": 180.0, "S": 0.0, "E": 270.0, "W": 90.0}


@dataclass(frozen=True)
class Member:
    """One object of a unit, in the unit frame."""

    kind: str
    u: float = 0.0
    v: float = 0.0
    turn: float = 0.0
    """Extra rotation relative to the unit (180 = faces the unit's back)."""
    width: float | None = None
    """Width override (tables and counters vary in length)."""


@dataclass(frozen=True)
class Unit:
    members: tuple[Member, ...]
    width: float
    depth: float
    access: float
    """Depth of the walkable zone kept free in front of the unit (or around it)."""
    around: bool = False
    """Keep the access zone on every side instead of the front only."""


class Planner:
    """Accumulates placements for one layout."""

    def __init__(self, rng: StableRng) -> None:
        self.rng = rng
        self.solid: list[Rect] = []
        self.clear: list[Rect] = []
        self.placed: list[WorldObject] = []
        self.counts: Counter[str] = Counter({"Door": 1})
        """Objects placed per ``objectType``: ids are ``Type_N`` in placement order (the exit
        is ``Door_1``)."""

    def against_wall(self, room: Room, unit: Unit, sides: str = "NESW") -> bool:
        """Place ``unit`` with its back to one of ``sides`` of ``room``; False if no room."""
        off = WALL_GAP + unit.depth / 2
        half = unit.width / 2

        def candidate() -> tuple[float, float, float]:
            side = self.rng.choice(sides)
            if side in "NS":
                along = self.rng.uniform(room.x0 + half, room.x1 - half)
                return along, room.z1 - off if side == "N" else room.z0 + off, SIDE_ROTATION[side]
            along = self.rng.uniform(room.z0 + half, room.z1 - half)
            return room.x1 - off if side == "E" else room.x0 + off, along, SIDE_ROTATION[side]

        return self._search(room, unit, candidate)

    def free(
        self, room: Room, unit: Unit, rotations: tuple[float, ...], *, spread: float | None = None
    ) -> bool:
        """Place ``unit`` anywhere in ``room`` (or within ``spread`` m of its centre)."""
        cx, cz = room.centre

        def candidate() -> tuple[float, float, float]:
            rot = self.rng.choice(rotations)
            if spread is None:
                return self.rng.uniform(room.x0, room.x1), self.rng.uniform(room.z0, room.z1), rot
            dx, dz = self.rng.uniform(-spread, spread), self.rng.uniform(-spread, spread)
            return cx + dx, cz + dz, rot

        return self._search(room, unit, candidate)

    def _search(
        self, room: Room, unit: Unit, candidate: Callable[[], tuple[float, float, float]]
    ) -> bool:
        """Try candidates in batches; commit the first that fits (False if none does)."""
        room_rect = np.array([room.x0, room.z0, room.x1, room.z1])
        for _ in range(CANDIDATES // BATCH):
            cands = np.array([candidate() for _ in range(BATCH)])
            x, z, rot = np.round(cands[:, 0], 2), np.round(cands[:, 1], 2), cands[:, 2]
            body = rects_at(x, z, unit.width, unit.depth, rot)
            if unit.around:
                grown = (unit.width + 2 * unit.access, unit.depth + 2 * unit.access)
                access = rects_at(x, z, *grown, rot)
            else:
                fx, fz = np.array([unit_vector(r) for r in rot]).T
                reach = (unit.depth + unit.access) / 2
                access = rects_at(x + fx * reach, z + fz * reach, unit.width, unit.access, rot)
            ok = _inside(body, room_rect) & _inside(access, room_rect)
            solid, clear = (
                np.array(r, dtype=float).reshape(-1, 4) for r in (self.solid, self.clear)
            )
            ok &= ~(_hits(body, solid) | _hits(access, solid) | _hits(body, clear))
            if ok.any():
                k = int(ok.argmax())
                self._commit(room, unit, float(x[k]), float(z[k]), float(rot[k]), tuple(access[k]))
                return True
        return False

    def _commit(self, room: Room, unit: Unit, x: float, z: float, rot: float, access: Rect) -> None:
        self.clear.append(access)
        for m in unit.members:
            kind = KINDS[m.kind]
            self.counts[kind.object_type] += 1
            object_id = f"{kind.object_type}_{self.counts[kind.object_type]}"
            mx, mz = local_to_world(x, z, rot, m.u, m.v)
            width = m.width if m.width is not None else kind.width
            obj = _object(
                m.kind,
                object_id,
                room.name,
                round(mx, 2),
                round(mz, 2),
                width,
                (rot + m.turn) % 360,
            )
            self.placed.append(obj)
            if obj.elevation == 0.0:
                self.solid.append(footprint(obj))


def _hits(rects: np.ndarray, others: np.ndarray) -> np.ndarray:
    """Whether each of ``rects`` overlaps any of ``others``."""
    return rects_overlap(rects, others).any(axis=1)


def _inside(rects: np.ndarray, room: np.ndarray) -> np.ndarray:
    return ((rects[:, :2] >= room[:2]) & (rects[:, 2:] <= room[2:])).all(axis=1)
