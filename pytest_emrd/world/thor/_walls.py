"""Wall segments of a rectangular-room layout, split where neighbouring rooms meet.

ProcTHOR wants one wall per straight boundary piece per room, and a door must sit on a
piece both its rooms own; so a room side is cut at every corner of another room lying on
it, and each piece has exactly one neighbour (a room, or the outside).
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass

from pytest_emrd.world._model import Layout, Room

EPS = 1e-6
"""Tolerance in metres for "on the same line" and "same corner"."""


@dataclass(frozen=True)
class WallPiece:
    """One straight wall piece of one room, in the room's winding order."""

    room: int
    """1-based index of the owning room (``room|<n>`` in the house)."""
    x0: float
    z0: float
    x1: float
    z1: float
    neighbour: int | None
    """Index of the room on the other side, or None for the outside."""

    @property
    def position_id(self) -> str:
        """ProcTHOR's order-free wall key ``minx|minz|maxx|maxz`` (2 decimals)."""
        return (
            f"{min(self.x0, self.x1):.2f}|{min(self.z0, self.z1):.2f}|"
            f"{max(self.x0, self.x1):.2f}|{max(self.z0, self.z1):.2f}"
        )

    @property
    def wall_id(self) -> str:
        return f"wall|{self.room}|{self.position_id}"

    @property
    def length(self) -> float:
        return math.hypot(self.x1 - self.x0, self.z1 - self.z0)

    @property
    def axis(self) -> str:
        """``"x"`` if the piece runs along x, ``"z"`` if along z."""
        return "x" if abs(self.z1 - self.z0) < EPS else "z"

    def offset_of(self, x: float, z: float) -> float | None:
        """Distance along the piece from its start to ``(x, z)``, or None if off the piece."""
        if self.axis == "x":
            if abs(z - self.z0) > EPS:
                return None
            along = (x - self.x0) if self.x1 >= self.x0 else (self.x0 - x)
        else:
            if abs(x - self.x0) > EPS:
                return None
            along = (z - self.z0) if self.z1 >= self.z0 else (self.z0 - z)
        return along if -EPS <= along <= self.length + EPS else None

    def distance_to(self, x: float, z: float) -> float:
        """Euclidean distance from ``(x, z)`` to the piece."""
        dx, dz = self.x1 - self.x0, self.z1 - self.z0
        t = ((x - self.x0) * dx + (z - self.z0) * dz) / (dx * dx + dz * dz)
        t = min(1.0, max(0.0, t))
        return math.hypot(x - (self.x0 + t * dx), z - (self.z0 + t * dz))


def corners(room: Room) -> tuple[tuple[float, float], ...]:
    """The floor polygon in ProcTHOR's winding: from the south-west corner, north first."""
    return ((room.x0, room.z0), (room.x0, room.z1), (room.x1, room.z1), (room.x1, room.z0))


def _covers(other: Room, x0: float, z0: float, x1: float, z1: float) -> bool:
    """Whether ``other`` has a side containing the segment's midpoint on the same line."""
    mx, mz = (x0 + x1) / 2, (z0 + z1) / 2
    if abs(z1 - z0) < EPS:  # horizontal segment
        on_line = abs(other.z0 - mz) < EPS or abs(other.z1 - mz) < EPS
        return on_line and other.x0 + EPS < mx < other.x1 - EPS
    on_line = abs(other.x0 - mx) < EPS or abs(other.x1 - mx) < EPS
    return on_line and other.z0 + EPS < mz < other.z1 - EPS


def _breaks(
    rooms: tuple[Room, ...], a: tuple[float, float], b: tuple[float, float]
) -> list[tuple[float, float]]:
    """Points from ``a`` to ``b`` (ends included, in order) where other rooms' corners cut it."""
    horizontal = abs(b[1] - a[1]) < EPS
    axis = 0 if horizontal else 1
    lo, hi = sorted((a[axis], b[axis]))
    inner = {
        c[axis]
        for other in rooms
        for c in corners(other)
        if abs(c[1 - axis] - a[1 - axis]) < EPS and lo + EPS < c[axis] < hi - EPS
    }
    along = sorted(inner, reverse=b[axis] < a[axis])
    cuts = [(v, a[1]) if horizontal else (a[0], v) for v in along]
    return [a, *cuts, b]


def wall_pieces(layout: Layout) -> tuple[WallPiece, ...]:
    """Every wall piece of every room, rooms numbered from 1 in layout order."""
    pieces: list[WallPiece] = []
    for n, room in enumerate(layout.rooms, start=1):
        others = tuple(r for r in layout.rooms if r is not room)
        poly = corners(room)
        for a, b in zip(poly, poly[1:] + poly[:1], strict=True):
            for (px0, pz0), (px1, pz1) in itertools.pairwise(_breaks(others, a, b)):
                neighbour = next(
                    (
                        i
                        for i, other in enumerate(layout.rooms, start=1)
                        if other is not room and _covers(other, px0, pz0, px1, pz1)
                    ),
                    None,
                )
                pieces.append(WallPiece(n, px0, pz0, px1, pz1, neighbour))
    return tuple(pieces)
