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

Division of labour: the rays are cast to the walls by
:meth:`~pytest_emrd.world._geometry.Walls.first_hit` (shared with visibility), the boxes in
view picked and ordered by :func:`~pytest_emrd.world._paint.object_boxes`; this module works
out, per column, the rows where the wall, the skirting and each box begin and end and the
shade-table code each shows, and fills a ``uint32`` frame of shade-table entries (ceiling,
walls, skirting, the floor's raster look-up, then the boxes), all in plain numpy: a few
milliseconds a frame, with nothing to compile.
"""

from __future__ import annotations

import functools
import io
import threading

import numpy as np
from PIL import Image

from pytest_emrd.world._catalog import WALL_HEIGHT
from pytest_emrd.world._conditions import ConditionParams
from pytest_emrd.world._geometry import right_of, unit
from pytest_emrd.world._model import WorldPose
from pytest_emrd.world._paint import (
    BOTTOM_FACE,
    EYE,
    FOCAL,
    HORIZON,
    NEAR,
    SIZE,
    TOP_FACE,
    X_FACE,
    Z_FACE,
    first_row,
    fog_weight,
    object_boxes,
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
WALL_BACK = 0.05
"""Metres before a wall hit where the wall's room is looked up (the side the eye is on)."""
FACE_LIGHT = np.array([0.74, 0.9, 1.0, 0.5])
"""Brightness of faces across x, across z, tops and undersides (``_paint.X_FACE`` ...)."""

_U = (np.arange(SIZE) + 0.5 - FOCAL) / FOCAL
_ROWS = np.arange(SIZE, dtype=np.int64)
_CEILING_DEPTH = FOCAL * (WALL_HEIGHT - EYE) / (HORIZON - (_ROWS[:HORIZON] + 0.5))
"""Depth of each ceiling row (each row of the ceiling lies at one depth)."""
_FLOOR_DEPTH = FOCAL * EYE / ((_ROWS[HORIZON:] + 0.5) - HORIZON)
"""Depth of each floor row."""
_K_TOP = FOCAL * (WALL_HEIGHT - EYE)
_K_SKIRT = FOCAL * (EYE - SKIRTING_HEIGHT)
_K_BOTTOM = FOCAL * EYE
"""The wall's top, the skirting's top and the wall's foot as ``focal * height above or below
the eye``: at depth ``t`` they lie ``k / t`` rows from the horizon."""


def palette(scene: Scene, params: ConditionParams, seed: int) -> np.ndarray:
    """``(L, 3)`` colours: the catalogue's, or under ``texture`` seeded random colours for
    walls, floors and every object material (ceiling and skirting kept)."""
    colors = scene.colors.astype(np.int64)
    if not params.randomize_palette:
        return colors
    labels = [label for label in range(WALL0, len(colors)) if not TILE0 <= label < PART0]
    colors[labels] = StableRng(seed * 7919 + 17).integers(20, 235, (len(labels), 3))
    colors[TILE0:PART0] = np.maximum(colors[FLOOR0:TILE0] - 12, 0)
    return colors


def shade_table(colors: np.ndarray, params: ConditionParams) -> np.ndarray:
    """``(L * 4 * 256,)`` look-up table: final RGB of ``(label, face, fog weight)``, each
    entry one ``uint32`` ``R | G << 8 | B << 16`` (one gather per pixel).

    ``rgb = rint(colour * face_light * light_factor * (255 - fog) / 255 + fog_rgb * fog / 255)``
    """
    weight = np.arange(256, dtype=np.float64)
    light = FACE_LIGHT * params.light_factor
    lit = np.asarray(colors)[:, None, None, :] * light[None, :, None, None]
    mix = lit * ((255.0 - weight) / 255.0)[None, None, :, None]
    mix = mix + np.array(params.fog_color, dtype=np.float64) * (weight / 255.0)[:, None]
    rgb = np.clip(np.rint(mix), 0, 255).astype(np.uint32).reshape(-1, 3)
    return rgb[:, 0] | rgb[:, 1] << 8 | rgb[:, 2] << 16


def render(scene: Scene, pose: WorldPose, params: ConditionParams, table: np.ndarray) -> np.ndarray:
    """The ``(512, 512, 3)`` uint8 frame seen from ``pose`` (``table`` from :func:`shade_table`)."""
    dx, dz = _rays(pose.heading)
    ox, oz = np.float64(pose.x), np.float64(pose.z)
    t_wall, along_x = scene.walls.first_hit(ox, oz, dx, dz)
    t_wall = np.minimum(t_wall, 1e3)
    buf = _buffer()
    _background(buf, scene, params, table, (dx, dz, t_wall, along_x, ox, oz))
    _boxes(buf, table, (dx, dz, t_wall), object_boxes(scene, pose, params), params)
    # R, G, B, 0 per pixel; Pillow reads the buffer in place and packs R, G, B.
    rgbx = Image.frombuffer(
        "RGBX", (SIZE, SIZE), buf.astype("<u4", copy=False), "raw", "RGBX", 0, 1
    )
    return np.frombuffer(rgbx.tobytes("raw", "RGB"), dtype=np.uint8).reshape(SIZE, SIZE, 3)


def _cell(a: np.ndarray, size: int) -> np.ndarray:
    """Raster index of coordinates already scaled to cells, clipped to ``[0, size)``
    (clipping first makes the truncation a floor)."""
    return np.minimum(np.maximum(a, 0.0), size - 1.0).astype(np.intp)


def _background(
    buf: np.ndarray,
    scene: Scene,
    params: ConditionParams,
    table: np.ndarray,
    view: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.float64, np.float64],
) -> None:
    """Ceiling, walls (their room's colour, shaded by orientation), skirting and floor.

    Per column, rows ``[0, top)`` are ceiling, ``[top, skirt)`` wall, ``[skirt, bottom)``
    skirting and the rest floor: every wall hit lies ahead (``0 < t_wall <= 1000``), the
    wall's top above the eye and the skirting's below, so ``top <= horizon <= skirt <=
    bottom``. Each ceiling and floor row lies at one depth; a floor pixel shows the raster
    cell under ``o + depth * d``. When every ray has the same ``dz`` (``dx``), as at the
    built-in world's headings, that coordinate's cell is the same along a row: it is worked
    out once per row, with the colours of that raster row (column) at the row's fog.
    """
    dx, dz, t_wall, along_x, ox, oz = view
    fog = (params.draw_distance, params.fog)
    room = scene.room_raster
    nz, nx = room.shape
    top = first_row(HORIZON - _K_TOP / t_wall)
    bottom = first_row(HORIZON + _K_BOTTOM / t_wall)
    skirt = first_row(HORIZON + _K_SKIRT / t_wall)
    hx = _cell((ox + (t_wall - WALL_BACK) * dx) * RASTER, nx)
    hz = _cell((oz + (t_wall - WALL_BACK) * dz) * RASTER, nz)
    face = np.where(along_x, Z_FACE, X_FACE)
    weight = fog_weight(t_wall, *fog)
    wall = table[(((WALL0 + room[hz, hx]) * 4 + face) << 8) | weight]
    foot = table[((SKIRTING * 4 + face) << 8) | weight]
    sky = table[((CEILING * 4 + Z_FACE) << 8) | fog_weight(_CEILING_DEPTH, *fog)]
    # Rows above every wall top are ceiling, rows between the highest and lowest top are
    # ragged; below the horizon the same for the skirting's and the foot's rows.
    t0, t1 = int(top.min()), int(top.max())
    buf[:t0] = sky[:t0, None]
    buf[t0:HORIZON] = wall
    np.copyto(buf[t0:t1], sky[t0:t1, None], where=top > _ROWS[t0:t1, None])
    s0, b0, b1 = int(skirt.min()), int(bottom.min()), int(bottom.max())
    buf[HORIZON:s0] = wall
    _floor(buf[b0:], scene, params, table, view, b0 - HORIZON)
    band, rows = buf[s0:b1], _ROWS[s0:b1, None]
    np.copyto(band, foot, where=bottom > rows)
    np.copyto(band, wall, where=skirt > rows)


def _floor(
    out: np.ndarray,
    scene: Scene,
    params: ConditionParams,
    table: np.ndarray,
    view: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.float64, np.float64],
    first: int,
) -> None:
    """Floor rows ``first`` (counted from the horizon) on, into ``out``: each pixel the
    entry of the raster cell under ``o + depth * d`` at the row's fog."""
    dx, dz, _, _, ox, oz = view
    floor = scene.floor_raster
    nz, nx = floor.shape
    depth = _FLOOR_DEPTH[first:]
    codes = ((floor * 4 + Z_FACE) << 8).ravel()
    row_fog = fog_weight(depth, params.draw_distance, params.fog)[:, None]
    depth = depth[:, None]
    if (dz == dz[0]).all():  # facing north or south: a row's floor lies on one raster row
        z = _cell((depth * dz[0] + oz) * RASTER, nz)
        lines = table[codes[z * nx + np.arange(nx)] | row_fog]
        cell = _cell((depth * dx + ox) * RASTER, nx)
    elif (dx == dx[0]).all():  # facing east or west: on one raster column
        x = _cell((depth * dx[0] + ox) * RASTER, nx)
        lines = table[codes[np.arange(nz) * nx + x] | row_fog]
        cell = _cell((depth * dz + oz) * RASTER, nz)
    else:
        x = _cell((depth * dx + ox) * RASTER, nx)
        z = _cell((depth * dz + oz) * RASTER, nz)
        np.take(table, codes[z * nx + x] | row_fog, out=out)
        return
    cell += np.arange(0, lines.size, lines.shape[1])[:, None]
    np.take(lines, cell, out=out)


def _boxes(
    buf: np.ndarray,
    table: np.ndarray,
    rays: tuple[np.ndarray, np.ndarray, np.ndarray],
    boxes: tuple[np.ndarray, ...],
    params: ConditionParams,
) -> None:
    """Paint the boxes back to front, each over the columns it can cover.

    A column's ray is inside a box from ``tn`` to ``tf`` (the slab test on ``x0..x1`` and
    ``z0..z1``); it hits the box when that interval lies between the near plane and the wall.
    The hit column shows rows ``[start, end)``: from the higher of the top edge's rows at
    ``tn`` and ``tf`` to the lower of the bottom edge's, in the underside's code when the box
    is above the eye, else the front face's (the face of the slab entered last). Then rows
    ``[start, over)`` are painted again: a box below the eye shows its top down to the top
    edge's row at ``tn``, where the front begins; one above it shows its front down to the
    bottom edge's row at ``tn``, where the underside begins.

    The slab test, rows and codes run at once over every (box, column) pair, laid end to
    end; the painting is one masked copy per face over each box's rectangle of rows and
    columns.
    """
    rel, y, lo, hi, label, extra = boxes
    if lo.size == 0:
        return
    dx, dz, t_wall = rays
    width = hi - lo
    offset = np.cumsum(width) - width
    k = np.repeat(np.arange(lo.size), width)
    cols = np.arange(k.size) + np.repeat(lo - offset, width)
    ray_x, ray_z, r = dx[cols], dz[cols], rel[k]
    with np.errstate(divide="ignore", invalid="ignore"):  # rays along a plane: inf or nan
        x0, x1 = r[:, 0] / ray_x, r[:, 2] / ray_x
        z0, z1 = r[:, 1] / ray_z, r[:, 3] / ray_z
    near_x, near_z = np.minimum(x0, x1), np.minimum(z0, z1)
    tn = np.maximum(near_x, near_z)
    tf = np.minimum(np.maximum(x0, x1), np.maximum(z0, z1))
    hit = (tn < tf) & (tn > NEAR) & (tn < t_wall[cols])
    tn, tf = np.where(hit, tn, 1.0), np.where(hit, tf, 1.0)
    y0, y1, kind = y[k, 0], y[k, 1], extra[k]
    start = first_row(np.minimum(HORIZON - y1 / tn, HORIZON - y1 / tf))
    end = first_row(np.maximum(HORIZON - y0 / tn, HORIZON - y0 / tf))
    over = np.where(
        kind == 1,
        first_row(HORIZON - y1 / tn),
        np.where(kind == 2, first_row(HORIZON - y0 / tn), start),
    )
    lit = ((label[k] * 4) << 8) | fog_weight(tn, params.draw_distance, params.fog)
    front = lit + (np.where(near_x > near_z, X_FACE, Z_FACE) << 8)
    first = table[np.where(kind == 2, lit + (BOTTOM_FACE << 8), front)]
    second = table[np.where(kind == 1, lit + (TOP_FACE << 8), front)]
    start = np.where(hit, start, SIZE)
    end = np.where(hit, end, 0)
    # Rows counted from ``start`` and read as unsigned: rows above it wrap to huge values,
    # so ``counted < span`` is ``start <= row < start + span`` in one comparison.
    span = np.maximum(end - start, 0).astype(np.uint64)
    over = np.maximum(np.minimum(over, end) - start, 0).astype(np.uint64)
    r0 = np.minimum.reduceat(start, offset).tolist()
    r1 = np.maximum.reduceat(end, offset).tolist()
    two = (extra != 0).tolist()
    for b, (c0, at, w) in enumerate(zip(lo.tolist(), offset.tolist(), width.tolist(), strict=True)):
        if r1[b] <= r0[b]:
            continue
        cut = slice(at, at + w)
        region = buf[r0[b] : r1[b], c0 : c0 + w]
        counted = (_ROWS[r0[b] : r1[b], None] - start[cut]).view(np.uint64)
        np.copyto(region, first[cut], where=counted < span[cut])
        if two[b]:
            np.copyto(region, second[cut], where=counted < over[cut])


@functools.lru_cache(maxsize=16)
def _rays(heading: float) -> tuple[np.ndarray, np.ndarray]:
    """Direction ``forward + right * u`` of each column's ray at ``heading`` (shared by every
    frame at that heading; nothing writes to them)."""
    fx, fz = unit(heading)
    rx, rz = right_of(heading)
    return fx + rx * _U, fz + rz * _U


def encode_jpeg(frame: np.ndarray, quality: int) -> bytes:
    """``frame`` as the JPEG at ``quality`` the model is sent."""
    out = io.BytesIO()
    Image.fromarray(frame).save(out, format="JPEG", quality=quality)
    return out.getvalue()


_LOCAL = threading.local()


def _buffer() -> np.ndarray:
    """This thread's uint32 scratch frame (a fresh megabyte per frame would cost page
    faults; nothing in it outlives a call to :func:`render`)."""
    buf: np.ndarray | None = getattr(_LOCAL, "buffer", None)
    if buf is None:
        buf = _LOCAL.buffer = np.empty((SIZE, SIZE), dtype=np.uint32)
    return buf
