"""Placing furniture without overlap: the occupancy bookkeeping behind the layout generator.

A *unit* is a group of objects placed together (a desk with its chair and laptop, the
conference table with its eight chairs, a counter with what stands on it) in the unit's
own frame: ``u`` metres to the right, ``v`` metres forward (the unit's front faces the
room). The planner keeps two lists of rectangles: ``solid`` floor footprints, and ``clear``
zones that must stay walkable (doorway approaches, each unit's access zone). A candidate
placement is accepted when its footprint overlaps neither, and its access zone overlaps no
solid footprint and lies inside the room; candidates are checked all at once with numpy.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pytest_emrd.world._catalog import KINDS
from pytest_emrd.world._geometry import Rect, local_to_world, rect_at, rects_overlap
from pytest_emrd.world._model import Room
from pytest_emrd.world._rng import StableRng

WALL_GAP = 0.02
"""Distance between a wall and the back of furniture standing against it."""
CANDIDATES = 48
"""Placements tried per unit before it is given up."""

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

    def reserve(self, rect: Rect) -> None:
        """Keep ``rect`` free of furniture (a doorway's approach zone)."""
        self.clear.append(rect)

    def against_wall(self, room: Room, unit: Unit, sides: str = "NESW") -> bool:
        """Place ``unit`` with its back to one of ``sides`` of ``room``; False if no room."""
        cands = []
        for _ in range(CANDIDATES):
            side = self.rng.choice(sides)
            rot = SIDE_ROTATION[side]
            half = unit.width / 2
            if side in "NS":
                along = self.rng.uniform(room.x0 + half, room.x1 - half)
                off = WALL_GAP + unit.depth / 2
                across = room.z1 - off if side == "N" else room.z0 + off
                cands.append((along, across, rot))
            else:
                along = self.rng.uniform(room.z0 + half, room.z1 - half)
                off = WALL_GAP + unit.depth / 2
                across = room.x1 - off if side == "E" else room.x0 + off
                cands.append((across, along, rot))
        return self._first_fit(room, unit, cands)

    def free(
        self, room: Room, unit: Unit, rotations: tuple[float, ...], *, spread: float | None = None
    ) -> bool:
        """Place ``unit`` anywhere in ``room`` (or within ``spread`` m of its centre)."""
        cx, cz = (room.x0 + room.x1) / 2, (room.z0 + room.z1) / 2
        cands = []
        for _ in range(CANDIDATES):
            rot = self.rng.choice(rotations)
            if spread is None:
                x = self.rng.uniform(room.x0, room.x1)
                z = self.rng.uniform(room.z0, room.z1)
            else:
                x = cx + self.rng.uniform(-spread, spread)
                z = cz + self.rng.uniform(-spread, spread)
            cands.append((x, z, rot))
        return self._first_fit(room, unit, cands)

    def _first_fit(self, room: Room, unit: Unit, cands: list[tuple[float, float, float]]) -> bool:
        cands = [(round(x, 2), round(z, 2), r) for x, z, r in cands]
        body = np.array([rect_at(x, z, unit.width, unit.depth, r) for x, z, r in cands])
        access = np.array([self._access_rect(unit, x, z, r) for x, z, r in cands])
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
        x, z, rot = cands[int(hits[0])]
        self._commit(room, unit, x, z, rot, tuple(access[int(hits[0])]))
        return True

    @staticmethod
    def _access_rect(unit: Unit, x: float, z: float, rot: float) -> Rect:
        if unit.around:
            return rect_at(x, z, unit.width + 2 * unit.access, unit.depth + 2 * unit.access, rot)
        ax, az = local_to_world(x, z, rot, 0.0, (unit.depth + unit.access) / 2)
        return rect_at(ax, az, unit.width, unit.access, rot)

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
    return (
        (rects[:, 0] >= room[0])
        & (rects[:, 1] >= room[1])
        & (rects[:, 2] <= room[2])
        & (rects[:, 3] <= room[3])
    )
