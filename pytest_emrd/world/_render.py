"""The first-person frame: a ray-caster, one ray per image column.

Camera: 512 x 512 pixels, 90 degree field of view horizontally and vertically, eye 1.5 m
above the floor, looking level; column ``c`` casts the ray ``forward + right * u`` with
``u = (c + 0.5 - 256) / 256``, so its parameter ``t`` is the depth along the view axis.

Drawing order: ceiling, floor (per-room colour, 0.5 m tiles) and walls (per-room colour,
skirting board, shaded by orientation) fill the frame; then the boxes of every object
within the visibility distance are painted back to front (objects by distance, items on
a desk or counter right after it, boxes bottom-up), each only over the columns it covers
and only where it is nearer than the wall. A box shows its front face, its top face when
below the eye, its underside when above. Surfaces are shaded by orientation and the
condition's light factor, then mixed with fog by depth (see
:mod:`pytest_emrd.world._conditions`).

Bit stability: headings are multiples of 90 degrees and positions centimetre values, so
every geometric quantity comes from ``+ - * /``, comparisons, ``ceil`` and integer casts
only (exactly rounded IEEE operations, no transcendental functions); colours come from a
look-up table built with explicit rounding (``np.rint``) and indexed by integer codes
(each pixel one ``(label * 4 + face) << 8 | fog`` code whose ``R, G, B`` bytes are copied
from the table: no arithmetic on colours). The same scene therefore renders to identical
bytes on every machine and numpy version.

Division of labour: numpy computes everything per image column (wall hits, the rows where
walls and boxes begin and end, their codes); the compiled :mod:`pytest_emrd.world._kernel`
fills the pixels (ceiling, floor tiles, walls, then the boxes back to front).
"""

from __future__ import annotations

import threading
from functools import lru_cache

import numpy as np

from pytest_emrd.world._catalog import WALL_HEIGHT
from pytest_emrd.world._conditions import ConditionParams
from pytest_emrd.world._geometry import right_of, unit
from pytest_emrd.world._model import WorldPose
from pytest_emrd.world._paint import (
    EYE,
    FOCAL,
    HORIZON,
    SIZE,
    X_FACE,
    Z_FACE,
    first_row,
    fog,
    object_spans,
)
from pytest_emrd.world._rng import StableRng
from pytest_emrd.world._scene import (
    CEILING,
    FLOOR0,
    PART0,
    RASTER,
    SKIRTING,
    TILE0,
    WALL0,
    Scene,
)

SKIRTING_HEIGHT = 0.1
FACE_LIGHT = np.array([0.74, 0.9, 1.0, 0.5])
"""Brightness of faces across x, across z, tops and undersides (``_paint.X_FACE`` ...)."""

_U = (np.arange(SIZE) + 0.5 - FOCAL) / FOCAL
_ROWS = np.arange(SIZE, dtype=np.int32)
_CEIL_DEPTH = FOCAL * (WALL_HEIGHT - EYE) / (HORIZON - (_ROWS[:HORIZON] + 0.5))
_FLOOR_DEPTH = FOCAL * EYE / ((_ROWS[HORIZON:] + 0.5) - HORIZON)


def palette(scene: Scene, params: ConditionParams, seed: int) -> np.ndarray:
    """``(L, 3)`` colours: the catalogue's, or under ``texture`` seeded random colours for
    walls, floors and every object material (ceiling and skirting kept)."""
    colors = scene.colors.astype(np.int64)
    if not params.randomize_palette:
        return colors
    rng = StableRng(seed * 7919 + 17)
    for label in range(WALL0, len(colors)):
        if not TILE0 <= label < PART0:
            colors[label] = [rng.integer(20, 235) for _ in range(3)]
    colors[TILE0:PART0] = np.maximum(colors[FLOOR0:TILE0] - 12, 0)
    return colors


def shade_table(colors: np.ndarray, params: ConditionParams) -> np.ndarray:
    """``(L * 4 * 256,)`` look-up table: final RGB of ``(label, face, fog weight)``, each
    entry one ``uint32`` ``R | G << 8 | B << 16`` (one gather per pixel).

    ``rgb = rint(colour * face_light * light_factor * (255 - fog) / 255 + fog_rgb * fog / 255)``
    """
    weight = np.arange(256, dtype=np.float64)
    lit = colors[:, None, None, :] * (FACE_LIGHT * params.light_factor)[None, :, None, None]
    mix = lit * ((255.0 - weight) / 255.0)[None, None, :, None]
    mix = mix + np.array(params.fog_color, dtype=np.float64) * (weight / 255.0)[:, None]
    rgb = np.clip(np.rint(mix), 0, 255).astype(np.uint32).reshape(-1, 3)
    return rgb[:, 0] | rgb[:, 1] << 8 | rgb[:, 2] << 16


def render(scene: Scene, pose: WorldPose, params: ConditionParams, table: np.ndarray) -> np.ndarray:
    """The ``(512, 512, 3)`` uint8 frame seen from ``pose`` (``table`` from :func:`shade_table`)."""
    from pytest_emrd.world._kernel import compose  # numba: loaded on the first frame only

    fx, fz = unit(pose.heading)
    rx, rz = right_of(pose.heading)
    dx, dz = fx + rx * _U, fz + rz * _U
    ox, oz = np.float64(pose.x), np.float64(pose.z)
    t_wall, along_x = scene.walls.first_hit(ox, oz, dx, dz)
    t_wall = np.minimum(t_wall, 1e3)
    ceiling, floor_fog = _fog_rows(params)
    walls = _walls(scene, ox, oz, (dx, dz, t_wall), along_x, params)
    rects, columns = object_spans(scene, pose, params, (dx, dz, t_wall))
    floor = (_floor_codes(scene), floor_fog, _FLOOR_DEPTH)
    eye = (dx, dz, ox, oz, float(RASTER))
    frame = np.empty((SIZE, SIZE, 3), dtype=np.uint8)
    compose(frame, _buffer(), table, ceiling, walls, floor, eye, rects, columns)
    return frame


_LOCAL = threading.local()


def _buffer() -> np.ndarray:
    """This thread's uint32 scratch frame, rows padded by one cache line (a fresh megabyte
    per frame would cost page faults; nothing in it outlives a call to :func:`render`)."""
    buf: np.ndarray | None = getattr(_LOCAL, "buffer", None)
    if buf is None:
        buf = _LOCAL.buffer = np.empty((SIZE, SIZE + 16), dtype=np.uint32)
    return buf


@lru_cache(maxsize=8)
def _fog_rows(params: ConditionParams) -> tuple[np.ndarray, np.ndarray]:
    """Codes of the ceiling rows and fog weights of the floor rows (each row of the ceiling
    and of the floor lies at one depth)."""
    ceiling = ((CEILING * 4 + Z_FACE) << 8) | fog(_CEIL_DEPTH, params)
    return ceiling, fog(_FLOOR_DEPTH, params)


@lru_cache(maxsize=32)
def _floor_codes(scene: Scene) -> np.ndarray:
    """``(nz, nx)`` int32 code (fog 0) of each floor cell of ``scene``."""
    return ((scene.floor_raster * 4 + Z_FACE) << 8).astype(np.int32)


def _to_cells(scaled: np.ndarray, size: int) -> np.ndarray:
    """Raster indices of coordinates already scaled to cells, clipped to ``[0, size)``
    (clipping first makes the integer cast a floor)."""
    return np.clip(scaled, 0.0, size - 1.0).astype(np.int32)


def _walls(
    scene: Scene,
    ox: np.float64,
    oz: np.float64,
    rays: tuple[np.ndarray, np.ndarray, np.ndarray],
    along_x: np.ndarray,
    params: ConditionParams,
) -> tuple[np.ndarray, ...]:
    """Per column the wall's ``top``, skirting's ``skirt`` and the wall foot's ``bottom``
    rows, and the codes of the wall (its room's colour, shaded by orientation) and of the
    skirting board: rows ``[top, skirt)`` are wall, ``[skirt, bottom)`` skirting. Every hit
    lies ahead (``0 < t_wall <= 1000``) and the wall's top is above the eye, the skirting's
    top below it, so ``top <= HORIZON <= skirt <= bottom`` in every column."""
    dx, dz, t_wall = rays
    top = first_row(HORIZON - FOCAL * (WALL_HEIGHT - EYE) / t_wall)
    bottom = first_row(HORIZON + FOCAL * EYE / t_wall)
    skirt = first_row(HORIZON + FOCAL * (EYE - SKIRTING_HEIGHT) / t_wall)
    nz, nx = scene.room_raster.shape
    hx = _to_cells((ox + (t_wall - 0.05) * dx) * RASTER, nx)
    hz = _to_cells((oz + (t_wall - 0.05) * dz) * RASTER, nz)
    face = np.where(along_x, Z_FACE, X_FACE)
    wall_fog = fog(t_wall, params)
    wall = ((((WALL0 + scene.room_raster[hz, hx]) * 4 + face) << 8) | wall_fog).astype(np.int32)
    skirting = (((SKIRTING * 4 + face) << 8) | wall_fog).astype(np.int32)
    return top, skirt, bottom, wall, skirting
