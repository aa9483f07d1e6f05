"""The first-person frame: a vectorised numpy ray-caster, one ray per image column.

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
(each pixel one ``(label * 4 + face) << 8 | fog`` code, one gather of packed ``R, G, B, 0``
entries, Pillow's raw unpacker dropping the pad byte: byte copies, no arithmetic). The
same scene therefore renders to identical bytes on every machine and numpy version.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np
from PIL import Image

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
    Workspace,
    fill_spans,
    first_row,
    fog,
    length,
    paint_objects,
    workspace,
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
WALL_BAND = 128
"""Image columns per band of the wall pass."""
FACE_LIGHT = np.array([0.74, 0.9, 1.0, 0.5])
"""Brightness of faces across x, across z, tops and undersides (``_paint.X_FACE`` ...)."""

_U = (np.arange(SIZE) + 0.5 - FOCAL) / FOCAL
_NEG_U = -_U
_ROWS = np.arange(SIZE, dtype=np.int32)
_CEIL_DEPTH = FOCAL * (WALL_HEIGHT - EYE) / (HORIZON - (_ROWS[:HORIZON] + 0.5))
_FLOOR_DEPTH = FOCAL * EYE / ((_ROWS[HORIZON:] + 0.5) - HORIZON)
_FLOOR_U = np.multiply.outer(_FLOOR_DEPTH, _U)
"""``depth * u`` of every floor pixel: under a cardinal heading the floor point's offset along
the axis that varies across the image is ``+-`` this, computed once (``x * -u == -(x * u)``
and ``o + -y == o - y`` exactly in IEEE arithmetic)."""


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
    entry the bytes ``R, G, B, 0`` packed in one ``uint32`` (one gather per pixel).

    ``rgb = rint(colour * face_light * light_factor * (255 - fog) / 255 + fog_rgb * fog / 255)``
    """
    weight = np.arange(256, dtype=np.float64)
    lit = colors[:, None, None, :] * (FACE_LIGHT * params.light_factor)[None, :, None, None]
    mix = lit * ((255.0 - weight) / 255.0)[None, None, :, None]
    mix = mix + np.array(params.fog_color, dtype=np.float64) * (weight / 255.0)[:, None]
    rgbx = np.zeros((*mix.shape[:3], 4), dtype=np.uint8)
    rgbx[..., :3] = np.clip(np.rint(mix), 0, 255)
    return rgbx.reshape(-1, 4).view(np.uint32)[:, 0]


def render(scene: Scene, pose: WorldPose, params: ConditionParams, table: np.ndarray) -> np.ndarray:
    """The ``(512, 512, 3)`` uint8 frame seen from ``pose`` (``table`` from :func:`shade_table`)."""
    fx, fz = unit(pose.heading)
    rx, rz = right_of(pose.heading)
    dx, dz = fx + rx * _U, fz + rz * _U
    t_wall, along_x = scene.walls.first_hit(np.float64(pose.x), np.float64(pose.z), dx, dz)
    rays = (dx, dz, np.minimum(t_wall, 1e3))
    ws = workspace()
    _background(scene, pose, params, rays, along_x, table, ws)
    paint_objects(scene, pose, params, rays, table, ws)
    # R, G, B, 0 per pixel; Pillow reads the buffer in place and packs R, G, B.
    rgbx = Image.frombuffer("RGBX", (SIZE, SIZE), ws.rgbx, "raw", "RGBX", 0, 1)
    rgb = rgbx.tobytes("raw", "RGB")
    return np.frombuffer(rgb, dtype=np.uint8).reshape(SIZE, SIZE, 3)


@lru_cache(maxsize=8)
def _fog_rows(params: ConditionParams) -> tuple[np.ndarray, np.ndarray]:
    """``(HORIZON, 1)`` ceiling codes and ``(SIZE - HORIZON, 1)`` fog weights of the floor
    rows (each row of the ceiling and of the floor lies at one depth)."""
    ceiling = ((CEILING * 4 + Z_FACE) << 8) | fog(_CEIL_DEPTH, params)
    return ceiling[:, None], fog(_FLOOR_DEPTH, params)[:, None]


@lru_cache(maxsize=32)
def _floor_codes(scene: Scene) -> np.ndarray:
    """``(nz, nx)`` int32 code (fog 0) of each floor cell of ``scene``."""
    return ((scene.floor_raster * 4 + Z_FACE) << 8).astype(np.int32)


def _to_cells(scaled: np.ndarray, size: int) -> np.ndarray:
    """Raster indices of coordinates already scaled to cells, clipped to ``[0, size)``
    (clipping first makes the integer cast a floor)."""
    return np.clip(scaled, 0.0, size - 1.0).astype(np.int32)


def _cells(
    origin: np.float64, step: np.ndarray, rows: slice, size: int, ws: Workspace, out: np.ndarray
) -> np.ndarray:
    """Raster cell of the floor points ``(origin + depth * step) * RASTER`` of floor rows
    ``rows`` along one axis: one column when ``step`` is the same for every image column
    (one axis of a cardinal heading), else in ``out`` (a workspace buffer)."""
    if np.all(step == step[0]):
        return _to_cells((np.multiply.outer(_FLOOR_DEPTH[rows], step[:1]) + origin) * RASTER, size)
    scaled = ws.scaled[rows]
    if np.array_equal(step, _U):
        np.add(_FLOOR_U[rows], origin, out=scaled)
    elif np.array_equal(step, _NEG_U):
        np.subtract(origin, _FLOOR_U[rows], out=scaled)
    else:
        np.multiply.outer(_FLOOR_DEPTH[rows], step, out=scaled)
        scaled += origin
    scaled *= RASTER
    np.clip(scaled, 0.0, size - 1.0, out=scaled)
    cells = out[rows]
    np.copyto(cells, scaled, casting="unsafe")  # the integer cast of astype
    return cells


def _background(
    scene: Scene,
    pose: WorldPose,
    params: ConditionParams,
    rays: tuple[np.ndarray, np.ndarray, np.ndarray],
    along_x: np.ndarray,
    table: np.ndarray,
    ws: Workspace,
) -> None:
    """Ceiling, floor (room colour, tiles) and walls (room colour, skirting) everywhere.

    Only the rows that can differ are computed: the floor below the lowest wall foot, the
    wall masks, per band of columns, between the band's highest wall top and lowest foot.
    """
    ox, oz = np.float64(pose.x), np.float64(pose.z)
    dx, dz, t_wall = rays
    top = first_row(HORIZON - FOCAL * (WALL_HEIGHT - EYE) / t_wall)
    bottom = first_row(HORIZON + FOCAL * EYE / t_wall)
    skirt = first_row(HORIZON + FOCAL * (EYE - SKIRTING_HEIGHT) / t_wall)
    first_floor = max(HORIZON, int(bottom.min()))
    ceiling, floor_fog = _fog_rows(params)
    ws.rgbx[:HORIZON] = np.take(table, ceiling)
    rows = slice(first_floor - HORIZON, None)
    codes = _floor_codes(scene)
    nz, nx = codes.shape
    cz, cx = _cells(oz, dz, rows, nz, ws, ws.cells[0]), _cells(ox, dx, rows, nx, ws, ws.cells[1])
    fog_rows = floor_fog[rows]
    if min(cz.shape[1], cx.shape[1]) == 1:
        # One axis is fixed along each image row (a cardinal heading): look up the colours
        # of the raster line each row lies on, then gather pixels from those lines.
        fixed, vary, grid = (cz, cx, codes) if cz.shape[1] == 1 else (cx, cz, codes.T)
        lines = np.take(table, np.take(grid, fixed[:, 0], axis=0) | fog_rows)
        vary += np.arange(len(lines))[:, None] * grid.shape[1]
        np.take(lines, vary, out=ws.rgbx[first_floor:], mode="clip")  # indices lie in range
    else:
        cz *= nx
        cz += cx
        np.take(table, codes.ravel()[cz] | fog_rows, out=ws.rgbx[first_floor:], mode="clip")

    hx = _to_cells((ox + (t_wall - 0.05) * dx) * RASTER, nx)
    hz = _to_cells((oz + (t_wall - 0.05) * dz) * RASTER, nz)
    face = np.where(along_x, Z_FACE, X_FACE)
    wall_fog = fog(t_wall, params)
    wall = ((((WALL0 + scene.room_raster[hz, hx]) * 4 + face) << 8) | wall_fog).astype(np.int32)
    skirting = (((SKIRTING * 4 + face) << 8) | wall_fog).astype(np.int32)
    # Per band of columns: rows [top, skirt) wall, [skirt, bottom) skirting. Rows that are
    # wall in every column of the band are copied whole; only the ragged rows near the top
    # and the foot go through masks: there, rows [top, bottom) skirting, then [top, skirt)
    # wall again (top <= 256 <= skirt in every column).
    wall_rgb = np.take(table, wall)
    spans = ((np.take(table, skirting), length(top, bottom)), (wall_rgb, length(top, skirt)))
    bands = [a.reshape(-1, WALL_BAND) for a in (top, skirt, bottom)]
    bounds = zip(
        range(0, SIZE, WALL_BAND),
        bands[0].min(axis=1).tolist(),
        bands[0].max(axis=1).tolist(),
        bands[1].min(axis=1).tolist(),
        bands[2].max(axis=1).tolist(),
        strict=True,
    )
    for c0, top0, top1, skirt0, bottom1 in bounds:
        cols, cut = (c0, c0 + WALL_BAND), slice(c0, c0 + WALL_BAND)
        band = [(value[cut], count[cut]) for value, count in spans]
        fill_spans(ws, (top0, top1), cols, top[cut], band[1:])
        ws.rgbx[top1:skirt0, cut] = wall_rgb[cut]
        fill_spans(ws, (skirt0, bottom1), cols, top[cut], band)
