"""Per-layout arrays shared by visibility, motion and the renderer (computed once per layout).

Palette labels: ``0`` ceiling, ``1`` skirting, then walls, floors and alternate floor tiles
per room (in :data:`~pytest_emrd.rooms.ROOM_NAMES` order), then one per ``(object, material)``.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from pytest_emrd.errors import ConfigError
from pytest_emrd.rooms import ROOM_NAMES
from pytest_emrd.world._catalog import (
    CEILING_COLOR,
    COLORS_OF,
    FLOOR_COLORS,
    SKIRTING_COLOR,
    WALL_COLORS,
)
from pytest_emrd.world._geometry import Walls, footprint, local_to_world, unit, walls_of
from pytest_emrd.world._model import Layout
from pytest_emrd.world._shapes import boxes_of

CEILING, SKIRTING, WALL0 = 0, 1, 2
FLOOR0 = WALL0 + len(ROOM_NAMES)
TILE0 = FLOOR0 + len(ROOM_NAMES)
PART0 = TILE0 + len(ROOM_NAMES)
AGENT_RADIUS = 0.25
"""The agent's footprint radius: standing spots keep this clear of walls and furniture."""
RASTER = 10
"""Cells per metre of :attr:`Scene.room_raster` (room bounds lie on a 10 cm grid)."""
TILE_CELLS = 5
"""Floor tile edge in raster cells (0.5 m)."""
MAX_OBJECTS = 255
"""Objects a frame tells apart: a pixel's fourth byte holds ``1 +`` its object's index."""
_TILE_SHIFT = 12
"""How much darker the alternate floor tiles are (of 255)."""


@dataclass(frozen=True, eq=False)
class Scene:
    layout: Layout
    walls: Walls
    rects: np.ndarray
    """``(N, 4)`` object footprints."""
    centres: np.ndarray
    """``(N, 2)``."""
    floor: np.ndarray
    """``(N,)`` bool: stands on the floor (blocks walking; not doorways, the exit, items)."""
    support: np.ndarray
    """``(N,)`` index of the object an item stands on (its own index otherwise)."""
    parts: np.ndarray
    """``(P, 6)`` world boxes ``x0, z0, x1, z1, y0, y1`` grouped by object."""
    part_object: np.ndarray
    part_label: np.ndarray
    part_facing: np.ndarray
    """``(P, 3)``: facing normal ``(nx, nz)`` and the box's face offset; normal 0 = always."""
    colors: np.ndarray
    """``(L, 3)`` uint8 baseline palette."""
    owners: np.ndarray
    """``(L,)`` ``1 +`` the index of the object a label paints, 0 for the room's labels."""
    index: dict[str, int]
    """object id -> index."""
    room_raster: np.ndarray
    """``(nz, nx)`` room index of each 10 cm cell (0 outside any room), for the renderer."""
    floor_raster: np.ndarray
    """``(nz, nx)`` floor label of each cell: the room's floor, alternate tiles darker."""
    landmarks: np.ndarray
    """``(N,)`` bool: doorways and the exit (category ``landmark``)."""

    def crowded(self, x: np.ndarray, z: np.ndarray, radius: float = AGENT_RADIUS) -> np.ndarray:
        """Whether a disc of ``radius`` at each point would touch floor furniture
        (footprints grown by the radius: slightly conservative at corners)."""
        f = self.rects[self.floor]
        px, pz = np.asarray(x, dtype=float)[..., None], np.asarray(z, dtype=float)[..., None]
        inside_x = (px > f[:, 0] - radius) & (px < f[:, 2] + radius)
        inside_z = (pz > f[:, 1] - radius) & (pz < f[:, 3] + radius)
        return (inside_x & inside_z).any(axis=-1)


def _support(layout: Layout, rects: np.ndarray, floor: np.ndarray) -> np.ndarray:
    support = np.arange(len(layout.objects))
    for i, o in enumerate(layout.objects):
        if o.elevation > 0:
            inside = floor & (rects[:, 0] <= o.x) & (rects[:, 2] >= o.x)
            inside &= (rects[:, 1] <= o.z) & (rects[:, 3] >= o.z)
            if inside.any():
                support[i] = inside.argmax()  # the first
    return support


@lru_cache(maxsize=32)
def scene_of(layout: Layout) -> Scene:
    """The scene arrays of ``layout`` (cached)."""
    objs = layout.objects
    if len(objs) > MAX_OBJECTS:
        raise ConfigError(
            f"layout with {len(objs)} objects; the renderer tells at most {MAX_OBJECTS} apart."
        )
    rects = np.array([footprint(o) for o in objs], dtype=float)
    floor = np.array([o.elevation == 0 and o.object_type not in ("Doorway", "Door") for o in objs])
    room_pos = {name: i for i, name in enumerate(ROOM_NAMES)}
    colors: list[tuple[int, int, int]] = [CEILING_COLOR, SKIRTING_COLOR]
    colors += [WALL_COLORS[r] for r in ROOM_NAMES] + [FLOOR_COLORS[r] for r in ROOM_NAMES]
    colors += [tuple(max(0, c - _TILE_SHIFT) for c in FLOOR_COLORS[r]) for r in ROOM_NAMES]
    labels: dict[tuple[int, str], int] = {}
    parts, part_obj, part_label, facing = [], [], [], []
    for i, o in enumerate(objs):
        kind_colors = COLORS_OF.get(o.object_type, {})
        fx, fz = unit(o.rotation)
        for b in boxes_of(o):
            ax, az = local_to_world(o.x, o.z, o.rotation, b.u0, b.v0)
            bx, bz = local_to_world(o.x, o.z, o.rotation, b.u1, b.v1)
            (x0, x1), (z0, z1) = sorted((ax, bx)), sorted((az, bz))
            parts.append((x0, z0, x1, z1, o.elevation + b.y0, o.elevation + b.y1))
            if b.role == "wall":
                room = layout.room_at((ax + bx) / 2, (az + bz) / 2) or o.room
                label = WALL0 + room_pos.get(room, 0)
            else:
                if (i, b.role) not in labels:
                    labels[(i, b.role)] = len(colors)
                    colors.append(tuple(kind_colors.get(b.role, o.color)))
                label = labels[(i, b.role)]
            part_obj.append(i)
            part_label.append(label)
            face_v = b.v1 if b.facing > 0 else b.v0
            facing.append((b.facing * fx, b.facing * fz, face_v * b.facing))
    owners = np.zeros(len(colors), dtype=np.int64)
    owners[list(labels.values())] = [i + 1 for i, _ in labels]
    return Scene(
        layout=layout,
        walls=walls_of(layout),
        rects=rects,
        centres=np.array([[o.x, o.z] for o in objs], dtype=float),
        floor=floor,
        support=_support(layout, rects, floor),
        parts=np.array(parts, dtype=float).reshape(-1, 6),
        part_object=np.array(part_obj, dtype=np.int64),
        part_label=np.array(part_label, dtype=np.int64),
        part_facing=np.array(facing, dtype=float).reshape(-1, 3),
        colors=np.array(colors, dtype=np.uint8),
        owners=owners,
        index={o.object_id: i for i, o in enumerate(objs)},
        room_raster=(rooms := _raster(layout)),
        floor_raster=_floor(rooms),
        landmarks=np.array([o.category == "landmark" for o in objs], dtype=bool),
    )


def _floor(rooms: np.ndarray) -> np.ndarray:
    iz, ix = np.indices(rooms.shape)
    tile = (ix // TILE_CELLS + iz // TILE_CELLS) & 1
    return np.where(tile == 1, TILE0, FLOOR0) + rooms


def _raster(layout: Layout) -> np.ndarray:
    nx, nz = round(layout.width * RASTER) + 1, round(layout.depth * RASTER) + 1
    gx, gz = np.meshgrid((np.arange(nx) + 0.5) / RASTER, (np.arange(nz) + 0.5) / RASTER)
    out = np.zeros((nz, nx), dtype=np.int64)
    for i, r in enumerate(layout.rooms):
        out[(gx >= r.x0) & (gx < r.x1) & (gz >= r.z0) & (gz < r.z1)] = i
    return out
