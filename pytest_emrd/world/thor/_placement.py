"""Where each layout object stands in THOR, and where the agent may start. Pure geometry.

THOR centres an asset's bounding box on the object's ``position``, so an object stands on
its support at ``y = support top + asset height / 2``, the support top being 0 or the top
of the desk or counter asset it stands on. :func:`place` shifts an object whose asset is
larger than its footprint the least distance that keeps it inside its room (and what stands
on it with it). The agent's start must be on THOR's absolute grid (``TeleportFull`` refuses
other points, and ``GetReachablePositions`` walks the grid from the start): the grid point
clear of every asset and wall nearest the builtin spawn (:func:`spawn_point`).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Final

import numpy as np

from pytest_emrd.world._geometry import Rect, rect_at
from pytest_emrd.world._model import Layout, Room, WorldObject
from pytest_emrd.world.thor._assets import DOOR_TYPES, Asset, choose_asset

GRID: Final = 0.25
"""THOR's ``gridSize`` (the backend's default)."""
CLEARANCE: Final = 0.3
"""Metres a spawn point keeps from every asset footprint and wall: THOR's default agent
capsule radius (0.2 m) plus slack for the capsule cast's skin."""
SUPPORT_TOLERANCE: Final = 0.02
"""How far (m) an item's elevation may differ from its support's EMRD height."""


@dataclass(frozen=True)
class Placed:
    """One layout object as THOR builds it."""

    asset: Asset
    x: float
    y: float
    """Centre of the asset's bounding box: support top + asset height / 2."""
    z: float
    rotation: float
    rect: Rect
    """World-axis footprint of the asset at ``(x, z)``."""


def _inside(rect: Rect, room: Room, margin: float) -> tuple[float, float]:
    """The least ``(dx, dz)`` that moves ``rect`` into ``room`` shrunk by ``margin``."""
    shifts = []
    for lo, hi, room_lo, room_hi in (
        (rect[0], rect[2], room.x0 + margin, room.x1 - margin),
        (rect[1], rect[3], room.z0 + margin, room.z1 - margin),
    ):
        if hi - lo > room_hi - room_lo:
            shifts.append((room_lo + room_hi) / 2 - (lo + hi) / 2)
        elif lo < room_lo:
            shifts.append(room_lo - lo)
        elif hi > room_hi:
            shifts.append(room_hi - hi)
        else:
            shifts.append(0.0)
    return shifts[0], shifts[1]


def _support(obj: WorldObject, floor: list[WorldObject]) -> WorldObject | None:
    """The floor object ``obj`` stands on: same room, its footprint holds ``obj``'s centre
    and its EMRD top is ``obj``'s elevation."""
    for other in floor:
        x0, z0, x1, z1 = rect_at(other.x, other.z, other.width, other.depth, other.rotation)
        if (
            other.room == obj.room
            and abs(other.height - obj.elevation) <= SUPPORT_TOLERANCE
            and x0 <= obj.x <= x1
            and z0 <= obj.z <= z1
        ):
            return other
    return None


def place(layout: Layout, overrides: Mapping[str, str] | None = None) -> dict[str, Placed]:
    """EMRD object id -> its THOR placement, for every object that is not a wall hole."""
    margin = layout.wall_thickness / 2
    rooms = {r.name: r for r in layout.rooms}
    solid = [o for o in layout.objects if o.object_type not in DOOR_TYPES]
    floor = [o for o in solid if o.elevation == 0]
    placed: dict[str, Placed] = {}
    shift: dict[str, tuple[float, float]] = {}
    for obj in sorted(solid, key=lambda o: o.elevation > 0):
        asset = choose_asset(obj.object_type, obj.width, obj.depth, obj.height, overrides)
        base, dx, dz = obj.elevation, 0.0, 0.0
        if obj.elevation > 0:
            support = _support(obj, floor)
            if support is not None:
                base = placed[support.object_id].asset.height
                dx, dz = shift[support.object_id]
        x, z = obj.x + dx, obj.z + dz
        rect = rect_at(x, z, asset.width, asset.depth, obj.rotation)
        ex, ez = _inside(rect, rooms[obj.room], margin)
        x, z = x + ex, z + ez
        shift[obj.object_id] = (x - obj.x, z - obj.z)
        placed[obj.object_id] = Placed(
            asset,
            x,
            base + asset.height / 2,
            z,
            obj.rotation % 360,
            rect_at(x, z, asset.width, asset.depth, obj.rotation),
        )
    return placed


def snap(value: float) -> float:
    """``value`` on THOR's grid (nearest multiple of :data:`GRID`)."""
    return round(round(value / GRID) * GRID, 4)


def spawn_point(
    room: Room, footprints: list[Rect], x: float, z: float
) -> tuple[float, float] | None:
    """The grid point in ``room`` nearest ``(x, z)`` at least :data:`CLEARANCE` from the
    room's walls and every footprint (None if the room has none)."""
    lo_x = math.ceil((room.x0 + CLEARANCE) / GRID) * GRID
    lo_z = math.ceil((room.z0 + CLEARANCE) / GRID) * GRID
    xs = np.arange(lo_x, room.x1 - CLEARANCE + 1e-9, GRID)
    zs = np.arange(lo_z, room.z1 - CLEARANCE + 1e-9, GRID)
    if xs.size == 0 or zs.size == 0:
        return None
    gx, gz = (a.ravel() for a in np.meshgrid(xs, zs))
    free = np.ones(gx.shape, dtype=bool)
    for x0, z0, x1, z1 in footprints:
        dx = np.maximum(np.maximum(x0 - gx, gx - x1), 0.0)
        dz = np.maximum(np.maximum(z0 - gz, gz - z1), 0.0)
        free &= np.hypot(dx, dz) >= CLEARANCE
    if not free.any():
        return None
    dist = np.round(np.hypot(gx - x, gz - z), 6)
    idx = np.flatnonzero(free)
    best = idx[np.lexsort((gz[idx], gx[idx], dist[idx]))[0]]
    return snap(float(gx[best])), snap(float(gz[best]))
