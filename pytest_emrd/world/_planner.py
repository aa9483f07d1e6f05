"""Placing furniture without overlap: the occupancy bookkeeping behind the layout generator.

A *unit* is a group of objects placed together (a desk with its chair and laptop) in its
own frame: ``u`` metres to the right, ``v`` forward (the front faces the room). A candidate
placement is accepted when its footprint overlaps neither a ``solid`` floor footprint nor a
``clear`` zone (doorway approaches, each unit's access zone), and its access zone overlaps
no solid footprint and lies inside the room.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from pytest_emrd.world._catalog import KINDS
from pytest_emrd.world._geometry import (
    Rect,
    headings_to_units,
    local_to_world,
    rect_at,
    rects_at,
    rects_overlap,
)
from pytest_emrd.world._model import Room
from pytest_emrd.world._rng import StableRng

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


@dataclass(frozen=True)
class Placed:
    """An object the planner placed (ids are assigned later)."""

    kind: str
    room: str
    x: float
    z: float
    rotation: float
    width: float


class Planner:
    """Accumulates placements for one layout."""

    def __init__(self, rng: StableRng) -> None:
        self.rng = rng
        self.solid: list[Rect] = []
        self.clear: list[Rect] = []
        self.placed: list[Placed] = []

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
        cx, cz = (room.x0 + room.x1) / 2, (room.z0 + room.z1) / 2

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
        """Try candidates in batches until one fits."""
        for _ in range(CANDIDATES // BATCH):
            if self._first_fit(room, unit, np.array([candidate() for _ in range(BATCH)])):
                return True
        return False

    def _first_fit(self, room: Room, unit: Unit, cands: np.ndarray) -> bool:
        x, z = np.round(cands[:, 0], 2), np.round(cands[:, 1], 2)
        rot = cands[:, 2]
        body = rects_at(x, z, unit.width, unit.depth, rot)
        if unit.around:
            access = rects_at(x, z, unit.width + 2 * unit.access, unit.depth + 2 * unit.access, rot)
        else:
            fx, fz = headings_to_units(rot)
            reach = (unit.depth + unit.access) / 2
            access = rects_at(x + fx * reach, z + fz * reach, unit.width, unit.access, rot)
        room_rect = np.array([room.x0, room.z0, room.x1, room.z1])
        ok = _inside(body, room_rect) & _inside(access, room_rect)
        if self.solid:
            solid = np.array(self.solid)
            ok &= ~rects_overlap(body, solid).any(axis=1)
            ok &= ~rects_overlap(access, solid).any(axis=1)
        if self.clear:
            ok &= ~rects_overlap(body, np.array(self.clear)).any(axis=1)
        hits = np.flatnonzero(ok)
        if hits.size == 0:
            return False
        k = int(hits[0])
        self._commit(room, unit, float(x[k]), float(z[k]), float(rot[k]), tuple(access[k]))
        return True

    def _commit(self, room: Room, unit: Unit, x: float, z: float, rot: float, access: Rect) -> None:
        self.clear.append(access)
        for m in unit.members:
            kind = KINDS[m.kind]
            mx, mz = local_to_world(x, z, rot, m.u, m.v)
            mrot = (rot + m.turn) % 360
            width = m.width if m.width is not None else kind.width
            placed = Placed(m.kind, room.name, round(mx, 2), round(mz, 2), mrot, width)
            self.placed.append(placed)
            if kind.elevation == 0.0:
                self.solid.append(rect_at(placed.x, placed.z, width, kind.depth, mrot))


def _inside(rects: np.ndarray, room: np.ndarray) -> np.ndarray:
    return ((rects[:, :2] >= room[:2]) & (rects[:, 2:] <= room[2:])).all(axis=1)
