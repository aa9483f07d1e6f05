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

from dataclasses import dataclass

import numpy as np
from PIL import Image

from pytest_emrd.world._catalog import WALL_HEIGHT
from pytest_emrd.world._conditions import ConditionParams
from pytest_emrd.world._geometry import right_of, unit
from pytest_emrd.world._model import WorldPose
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

SIZE = 512
FOCAL = SIZE / 2
HORIZON = SIZE // 2
EYE = 1.5
SKIRTING_HEIGHT = 0.1
NEAR = 0.05

#: Surface orientations and their brightness: faces across x (east/west), across z
#: (north/south), tops, undersides. A pixel's code is ``(label * 4 + face) << 8 | fog``.
X_FACE, Z_FACE, TOP_FACE, BOTTOM_FACE = 0, 1, 2, 3
FACE_LIGHT = np.array([0.74, 0.9, 1.0, 0.5])

_U = (np.arange(SIZE) + 0.5 - FOCAL) / FOCAL
_ROWS = np.arange(SIZE, dtype=np.int32)
_ROW_COL = _ROWS[:, None]
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
    entry the bytes ``R, G, B, 0`` packed in one ``uint32`` (one gather per pixel).

    ``rgb = rint(colour * face_light * light_factor * (255 - fog) / 255 + fog_rgb * fog / 255)``
    """
    fog = np.arange(256, dtype=np.float64)
    lit = colors[:, None, None, :] * (FACE_LIGHT * params.light_factor)[None, :, None, None]
    mix = lit * ((255.0 - fog) / 255.0)[None, None, :, None]
    mix = mix + np.array(params.fog_color, dtype=np.float64) * (fog / 255.0)[:, None]
    rgbx = np.zeros((*mix.shape[:3], 4), dtype=np.uint8)
    rgbx[..., :3] = np.clip(np.rint(mix), 0, 255)
    return rgbx.reshape(-1, 4).view(np.uint32)[:, 0]


def _fog(depth: np.ndarray, params: ConditionParams) -> np.ndarray:
    """Fog weight 0..255 of surfaces at ``depth``."""
    ratio = depth / params.visibility_distance
    return np.rint(np.minimum(1.0, params.fog * ratio * ratio) * 255.0).astype(np.int32)


def _row(a: np.ndarray) -> np.ndarray:
    """First image row whose pixel centre lies at or below the continuous row ``a``."""
    return np.clip(np.ceil(a - 0.5), 0, SIZE).astype(np.int32)


@dataclass(frozen=True, eq=False)
class _View:
    """One frame being drawn: the camera rays, their wall hits and the output buffer."""

    pose: WorldPose
    params: ConditionParams
    dx: np.ndarray
    """``(512,)`` ray direction per column (forward component 1, so ``t`` is depth)."""
    dz: np.ndarray
    t_wall: np.ndarray
    """``(512,)`` depth of the nearest wall per column."""
    along_x: np.ndarray
    """``(512,)`` whether that wall runs along x."""
    code: np.ndarray
    """``(512, 512)`` int32 pixel codes ``(label * 4 + face) << 8 | fog``."""


def render(scene: Scene, pose: WorldPose, params: ConditionParams, table: np.ndarray) -> np.ndarray:
    """The ``(512, 512, 3)`` uint8 frame seen from ``pose`` (``table`` from :func:`shade_table`)."""
    fx, fz = unit(pose.heading)
    rx, rz = right_of(pose.heading)
    dx, dz = fx + rx * _U, fz + rz * _U
    t_wall, along_x = scene.walls.first_hit(np.float64(pose.x), np.float64(pose.z), dx, dz)
    view = _View(
        pose,
        params,
        dx,
        dz,
        np.minimum(t_wall, 1e3),
        along_x,
        code=np.empty((SIZE, SIZE), dtype=np.int32),
    )
    _background(scene, view)
    _objects(scene, view)
    # R, G, B, 0 per pixel; Pillow's raw unpacker drops the pad byte into packed RGB.
    rgbx = np.take(table, view.code)
    rgb = Image.frombytes("RGB", (SIZE, SIZE), rgbx, "raw", "RGBX").tobytes()
    return np.frombuffer(rgb, dtype=np.uint8).reshape(SIZE, SIZE, 3)


def _to_cells(scaled: np.ndarray, size: int) -> np.ndarray:
    """Raster indices of coordinates already scaled to cells, clipped to ``[0, size)``
    (clipping first makes the integer cast a floor)."""
    return np.clip(scaled, 0.0, size - 1.0).astype(np.int32)


def _cells(origin: np.float64, step: np.ndarray, depth: np.ndarray, size: int) -> np.ndarray:
    """Raster cell of floor points ``(origin + depth * step) * RASTER`` along one axis (in
    place, one buffer); one column when ``step`` is the same for every image column (one
    axis of a cardinal heading)."""
    if np.all(step == step[0]):
        step = step[:1]
    scaled = np.multiply.outer(depth, step)
    scaled += origin
    scaled *= RASTER
    np.clip(scaled, 0.0, size - 1.0, out=scaled)
    return scaled.astype(np.int32)


def _background(scene: Scene, view: _View) -> None:
    """Ceiling, floor (room colour, tiles) and walls (room colour, skirting) everywhere.

    Only the rows that can differ are computed: the floor below the lowest wall foot, the
    wall masks between the highest wall top and the lowest wall foot.
    """
    ox, oz, dx, dz = np.float64(view.pose.x), np.float64(view.pose.z), view.dx, view.dz
    t_wall, params, code = view.t_wall, view.params, view.code
    top = _row(HORIZON - FOCAL * (WALL_HEIGHT - EYE) / t_wall)
    bottom = _row(HORIZON + FOCAL * EYE / t_wall)
    skirt = _row(HORIZON + FOCAL * (EYE - SKIRTING_HEIGHT) / t_wall)
    r0, r1, first_floor = int(top.min()), int(bottom.max()), max(HORIZON, int(bottom.min()))
    code[:HORIZON] = (((CEILING * 4 + Z_FACE) << 8) | _fog(_CEIL_DEPTH, params))[:, None]
    rooms = scene.room_raster
    nz, nx = rooms.shape
    depth = _FLOOR_DEPTH[first_floor - HORIZON :]
    cell = _cells(oz, dz, depth, nz) * nx + _cells(ox, dx, depth, nx)
    floor = code[first_floor:]
    np.take(((scene.floor_raster * 4 + Z_FACE) << 8).astype(np.int32), cell, out=floor)
    floor |= _fog(depth, params)[:, None]

    hx = _to_cells((ox + (t_wall - 0.05) * dx) * RASTER, nx)
    hz = _to_cells((oz + (t_wall - 0.05) * dz) * RASTER, nz)
    face = np.where(view.along_x, Z_FACE, X_FACE)
    wall_fog = _fog(t_wall, params)
    wall = ((((WALL0 + rooms[hz, hx]) * 4 + face) << 8) | wall_fog).astype(np.int32)
    np.copyto(code[r0:r1], wall, where=_below(r0, r1, top) < _length(top, bottom))
    s0 = max(HORIZON, int(skirt.min()))
    skirting = (((SKIRTING * 4 + face) << 8) | wall_fog).astype(np.int32)
    np.copyto(code[s0:r1], skirting, where=_below(s0, r1, skirt) < _length(skirt, bottom))


def _dist2(rects: np.ndarray, pose: WorldPose) -> np.ndarray:
    """Squared distance from the agent to the nearest point of each rectangle."""
    ddx = np.maximum(np.maximum(rects[:, 0] - pose.x, pose.x - rects[:, 2]), 0.0)
    ddz = np.maximum(np.maximum(rects[:, 1] - pose.z, pose.z - rects[:, 3]), 0.0)
    return ddx * ddx + ddz * ddz


def _draw_order(scene: Scene, pose: WorldPose, parts: np.ndarray, objs: np.ndarray) -> np.ndarray:
    """Indices into ``parts`` back to front: by the distance of the object (an item on a
    desk takes its desk's), then bottom-up, then farther boxes first."""
    group = _dist2(scene.rects[scene.support[objs]], pose)
    return np.lexsort((-_dist2(parts[:, :4], pose), parts[:, 4], -group))


def _shown_parts(scene: Scene, pose: WorldPose, params: ConditionParams) -> np.ndarray:
    """Boxes of objects within the visibility distance, minus faces turned away."""
    near = (_dist2(scene.rects, pose) <= params.visibility_distance**2)[scene.part_object]
    nf = scene.part_facing
    cen = scene.centres[scene.part_object]
    side = (pose.x - cen[:, 0]) * nf[:, 0] + (pose.z - cen[:, 1]) * nf[:, 1]
    shown = near & (((nf[:, 0] == 0) & (nf[:, 1] == 0)) | (side > nf[:, 2]))
    return np.flatnonzero(shown & _in_view(scene.parts, pose))


def _in_view(parts: np.ndarray, pose: WorldPose) -> np.ndarray:
    """False for boxes wholly outside one edge of the view wedge (conservative cull)."""
    fx, fz = unit(pose.heading)
    rx, rz = right_of(pose.heading)
    cx = parts[:, [0, 0, 2, 2]] - pose.x
    cz = parts[:, [1, 3, 1, 3]] - pose.z
    fwd, lat = cx * fx + cz * fz, cx * rx + cz * rz
    return ~((fwd <= NEAR).all(axis=1) | (lat > fwd).all(axis=1) | (lat < -fwd).all(axis=1))


def _objects(scene: Scene, view: _View) -> None:
    """Paint the boxes of nearby objects back to front, over the columns each one covers."""
    pose, params, dx, dz, code = view.pose, view.params, view.dx, view.dz, view.code
    sel = _shown_parts(scene, pose, params)
    if sel.size == 0:
        return
    p = scene.parts[sel]
    ax, bx = (p[:, 0:1] - pose.x) / dx, (p[:, 2:3] - pose.x) / dx
    az, bz = (p[:, 1:2] - pose.z) / dz, (p[:, 3:4] - pose.z) / dz
    tminx, tminz = np.minimum(ax, bx), np.minimum(az, bz)
    tn = np.maximum(tminx, tminz)
    tf = np.minimum(np.maximum(ax, bx), np.maximum(az, bz))
    hit = (tn < tf) & (tn > NEAR) & (tn < view.t_wall)
    keep = np.flatnonzero(hit.any(axis=1))
    if keep.size == 0:
        return
    p, tn, tf, hit, sel = p[keep], tn[keep], tf[keep], hit[keep], sel[keep]
    tn = np.where(hit, tn, 1.0)
    tf = np.where(hit, tf, 1.0)
    y0, y1 = p[:, 4:5] - EYE, p[:, 5:6] - EYE
    a_n, a_f = HORIZON - FOCAL * y1 / tn, HORIZON - FOCAL * y1 / tf
    b_n, b_f = HORIZON - FOCAL * y0 / tn, HORIZON - FOCAL * y0 / tf
    start = np.where(hit, _row(np.minimum(a_n, a_f)), SIZE)
    end = np.where(hit, _row(np.maximum(b_n, b_f)), 0)
    fog_cols = _fog(tn, params)
    base = scene.part_label[sel].astype(np.int32)[:, None] * 4
    front = ((base + np.where(tminx[keep] > tminz[keep], X_FACE, Z_FACE)) << 8) | fog_cols
    has_top, has_bottom = y1 < 0, y0 > 0
    # Each column of a box is painted as rows [start, end) in one code (the underside when
    # the box is above the eye, else the front face), then its first `over` rows again in a
    # second code: the top face down to where the front begins, or the front face down to
    # where the underside begins.
    first = np.where(has_bottom, ((base + BOTTOM_FACE) << 8) | fog_cols, front)
    second = np.where(has_top, ((base + TOP_FACE) << 8) | fog_cols, front)
    over_end = np.where(has_top, _row(a_n), np.where(has_bottom, _row(b_n), start))
    span = _length(start, end)
    over = _length(start, np.minimum(over_end, end))
    bounds = zip(
        start.min(axis=1).tolist(),
        end.max(axis=1).tolist(),
        np.argmax(hit, axis=1).tolist(),
        (SIZE - np.argmax(hit[:, ::-1], axis=1)).tolist(),
        (has_top | has_bottom)[:, 0].tolist(),
        strict=True,
    )
    boxes = list(bounds)
    for k in _draw_order(scene, pose, p, scene.part_object[sel]).tolist():
        r0, r1, c0, c1, two_faces = boxes[k]
        if r1 <= r0:
            continue
        below = _below(r0, r1, start[k, c0:c1])
        region = code[r0:r1, c0:c1]
        np.copyto(region, first[k, c0:c1], where=below < span[k, c0:c1])
        if two_faces:
            np.copyto(region, second[k, c0:c1], where=below < over[k, c0:c1])


def _length(first: np.ndarray, end: np.ndarray) -> np.ndarray:
    """Rows in ``[first, end)`` per column (0 when empty), as uint32 for :func:`_below`."""
    return np.maximum(end - first, 0).astype(np.uint32)


def _below(r0: int, r1: int, first: np.ndarray) -> np.ndarray:
    """``(r1 - r0, columns)``: rows ``r0..r1`` counted from ``first`` of each column, as
    uint32, so rows above ``first`` wrap to huge values and ``_below(...) < _length(first,
    end)`` is exactly ``first <= row < end`` in one comparison."""
    return (_ROW_COL[r0:r1] - first).view(np.uint32)
