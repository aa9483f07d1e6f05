"""The first-person frame: a ray-caster, one ray per image column.

Camera: 512 x 512 pixels, 90 degree field of view both ways, eye 1.5 m above the floor,
looking level; column ``c`` casts the ray ``forward + right * u`` with
``u = (c + 0.5 - 256) / 256``, so its parameter ``t`` is the depth along the view axis.
Ceiling, floor (per-room colour, 0.5 m tiles) and walls (per-room colour, skirting) fill
the frame; then the boxes of nearby objects (:func:`object_boxes`) are painted back to
front, each where it is nearer than the wall, over the image columns it can cover (a
conservative range from its extent in the camera frame). Surfaces are shaded by
orientation and the condition's light factor, then mixed with fog by depth, total at the
visibility distance (landmarks: doorway frames, the exit, at the drawn distance).

Visibility, one rule: a pixel is *legible* when it differs by at least :data:`MIN_CONTRAST`
levels in some channel from what the frame would show there without the object it shows.
Each pixel's fourth byte holds ``1 +`` the index of that object (0: the room); painting a
box over another object's or the room's pixel keeps that pixel's colour in a second
buffer, so :func:`render` counts legible pixels per object in one pass, and
:mod:`~pytest_emrd.world._visibility` reads visibility from the counts.

Bit stability: headings are multiples of 90 degrees and positions centimetre values, so
every geometric quantity comes from ``+ - * /``, comparisons, ``ceil`` and integer casts
(exactly rounded IEEE operations); each pixel is one ``(label * 4 + face) << 8 | fog`` code
whose bytes are copied from a table built with explicit rounding (``np.rint``). The same
scene renders to identical bytes on every machine and numpy version.
"""

from __future__ import annotations

import functools
import itertools
import threading

import numpy as np
from PIL import Image

from pytest_emrd.world._catalog import WALL_HEIGHT
from pytest_emrd.world._conditions import ConditionParams
from pytest_emrd.world._geometry import right_of, unit
from pytest_emrd.world._model import WorldPose
from pytest_emrd.world._rng import StableRng
from pytest_emrd.world._scene import CEILING, FLOOR0, PART0, RASTER, SKIRTING, TILE0, WALL0, Scene

SIZE = 512
FOCAL = SIZE / 2
HORIZON = SIZE // 2
EYE = 1.5
NEAR = 0.05

MIN_CONTRAST = 24
"""Levels a legible pixel differs, in some channel, from what the frame shows there without
its object: the change a person reads as an edge (the legibility test's threshold)."""

#: Surface orientations: faces across x (east/west), across z (north/south), tops,
#: undersides. A surface's code is ``(label * 4 + face) << 8 | fog``, its colour
#: ``table[code]`` (:func:`shade_table`).
X_FACE, Z_FACE, TOP_FACE, BOTTOM_FACE = 0, 1, 2, 3


def fog_weight(depth: np.ndarray, reach: float | np.ndarray) -> np.ndarray:
    """Fog weight 0..255 (int64) of surfaces at ``depth``: ``rint(min(1, (d / r)^4) * 255)``
    with ``r`` the surface's reach: clear near, total at ``r``."""
    ratio = depth / reach
    square = ratio * ratio
    return np.rint(np.minimum(1.0, square * square) * 255.0).astype(np.int64)


def first_row(a: np.ndarray) -> np.ndarray:
    """First image row (in ``[0, 512]``, int16) whose pixel centre lies at or below row
    ``a``."""
    return np.minimum(np.maximum(np.ceil(a - 0.5), 0.0), float(SIZE)).astype(np.int16)


def _dist2(rects: np.ndarray, x: float, z: float) -> np.ndarray:
    """Squared distance from ``(x, z)`` to the nearest point of each rectangle."""
    ddx = np.maximum(np.maximum(rects[:, 0] - x, x - rects[:, 2]), 0.0)
    ddz = np.maximum(np.maximum(rects[:, 1] - z, z - rects[:, 3]), 0.0)
    return ddx * ddx + ddz * ddz


def object_boxes(scene: Scene, pose: WorldPose, params: ConditionParams) -> tuple[np.ndarray, ...]:
    """The boxes of nearby objects as :func:`render` paints them.

    A box is kept when its object lies within the drawn distance, it shows from the eye's
    side, and it may cover some column. Boxes are ordered farthest first by the footprint of
    the object their object stands on (an item on a desk takes its desk's), then lowest
    first, then farthest first by their own footprint, ties in scene order.

    Per box: ``(n, 4)`` planes ``x0, z0, x1, z1`` relative to the eye, ``(n, 2)``
    ``focal * (y - eye)`` of its bottom and top, the first and one past the last column its
    rays can hit, its label, and which extra face shows: 1 the top (below the eye), 2 the
    underside (above the eye), 0 neither; its fog's reach (:func:`fog_weight`).
    """
    x, z = float(pose.x), float(pose.z)
    parts, facing = scene.parts, scene.part_facing
    centre = scene.centres[scene.part_object]
    always = (facing[:, 0] == 0) & (facing[:, 1] == 0)
    near = (_dist2(scene.rects, x, z) <= params.draw_distance**2)[scene.part_object]
    side = (x - centre[:, 0]) * facing[:, 0] + (z - centre[:, 1]) * facing[:, 1]
    fx, fz = unit(pose.heading)
    rx, rz = right_of(pose.heading)
    cx, cz = parts[:, [0, 0, 2, 2]] - x, parts[:, [1, 3, 1, 3]] - z
    fwd, lat = cx * fx + cz * fz, cx * rx + cz * rz
    out_of_view = (fwd <= NEAR).all(axis=1) | (lat > fwd).all(axis=1) | (lat < -fwd).all(axis=1)
    sel = np.flatnonzero(near & (always | (side > facing[:, 2])) & ~out_of_view)
    fwd, lat = fwd[sel], lat[sel]
    f0, f1 = np.maximum(fwd.min(axis=1), NEAR), fwd.max(axis=1)
    l0, l1 = lat.min(axis=1), lat.max(axis=1)
    u0, u1 = np.minimum(l0 / f0, l0 / f1), np.maximum(l1 / f0, l1 / f1)
    lo = np.clip(np.floor(u0 * FOCAL + (FOCAL - 0.5)) - 1, 0, SIZE).astype(np.int64)
    hi = np.clip(np.ceil(u1 * FOCAL + (FOCAL - 0.5)) + 2, 0, SIZE).astype(np.int64)
    wide = hi > lo
    sel, lo, hi = sel[wide], lo[wide], hi[wide]
    group = _dist2(scene.rects[scene.support[scene.part_object[sel]]], x, z)
    order = np.lexsort((-_dist2(parts[sel, :4], x, z), parts[sel, 4], -group))
    sel, lo, hi = sel[order], lo[order], hi[order]
    p = parts[sel]
    extra = np.where(p[:, 5] < EYE, 1, np.where(p[:, 4] > EYE, 2, 0))
    rel = p[:, :4] - (x, z, x, z)
    reach = np.where(
        scene.landmarks[scene.part_object[sel]], params.draw_distance, params.visibility_distance
    )
    return rel, FOCAL * (p[:, 4:6] - EYE), lo, hi, scene.part_label[sel], extra, reach


FOGGED = 255
"""Fog weight of a surface the fog hides: every label's entry is then the fog colour (and
the room's labels own nothing), so ``table[FOGGED]`` is the fog itself."""
SKIRTING_HEIGHT = 0.1
WALL_BACK = 0.05
"""Metres before a wall hit where the wall's room is looked up (the side the eye is on)."""
FACE_LIGHT = np.array([0.74, 0.9, 1.0, 0.5])
"""Brightness of faces across x, across z, tops and undersides (:data:`X_FACE` ...)."""

_U = (np.arange(SIZE) + 0.5 - FOCAL) / FOCAL
_ROWS = np.arange(SIZE, dtype=np.int16)
_CEILING_DEPTH = FOCAL * (WALL_HEIGHT - EYE) / (HORIZON - (_ROWS[:HORIZON] + 0.5))
"""Depth of each ceiling row (each row of the ceiling lies at one depth)."""
_FLOOR_DEPTH = FOCAL * EYE / ((_ROWS[HORIZON:] + 0.5) - HORIZON)
"""Depth of each floor row."""
_K_EDGES = FOCAL * np.array([[EYE - WALL_HEIGHT], [EYE - SKIRTING_HEIGHT], [EYE]])
"""The wall's top, the skirting's top and the wall's foot as ``focal * depth below the eye``:
at depth ``t`` they lie ``k / t`` rows below the horizon."""


def palette(scene: Scene, params: ConditionParams, seed: int) -> np.ndarray:
    """``(L, 3)`` colours: the catalogue's, or under ``texture`` seeded random colours for
    walls, floors and every object material (ceiling and skirting kept)."""
    colors = scene.colors.astype(np.int64)
    if not params.randomize_palette:
        return colors
    labels = [label for label in range(WALL0, len(colors)) if not TILE0 <= label < PART0]
    rng = StableRng(seed * 7919 + 17)
    colors[labels] = [[rng.integer(20, 235) for _ in range(3)] for _ in labels]
    colors[TILE0:PART0] = np.maximum(colors[FLOOR0:TILE0] - 12, 0)
    return colors


def shade_table(colors: np.ndarray, params: ConditionParams, owners: np.ndarray) -> np.ndarray:
    """``(L * 4 * 256,)`` look-up table: final RGB of ``(label, face, fog weight)`` as one
    little-endian ``uint32`` ``R | G << 8 | B << 16 | owner << 24``, ``rgb = rint(colour *
    face_light * light_factor * (255 - fog) / 255 + fog_rgb * fog / 255)``; ``owner`` is
    ``owners[label]`` (``1 +`` its object's index, 0 for the room)."""
    weight = np.arange(256, dtype=np.float64)
    light = FACE_LIGHT * params.light_factor
    lit = np.asarray(colors)[:, None, None, :] * light[None, :, None, None]
    mix = lit * ((255.0 - weight) / 255.0)[None, None, :, None]
    mix = mix + np.array(params.fog_color, dtype=np.float64) * (weight / 255.0)[:, None]
    rgb = np.clip(np.rint(mix), 0, 255).astype(np.uint32).reshape(len(owners), -1, 3)
    owner = np.asarray(owners, dtype=np.uint32)[:, None]
    return (rgb[..., 0] | rgb[..., 1] << 8 | rgb[..., 2] << 16 | owner << 24).ravel().astype("<u4")


def render(
    scene: Scene, pose: WorldPose, params: ConditionParams, table: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """The ``(512, 512, 3)`` uint8 frame seen from ``pose`` (``table`` from :func:`shade_table`)
    and, per object of the scene, how many of its pixels are legible."""
    dx, dz = _rays(pose.heading)
    ox, oz = np.float64(pose.x), np.float64(pose.z)
    t_wall, along_x = scene.walls.first_hit(ox, oz, dx, dz)
    t_wall = np.minimum(t_wall, 1e3)
    buf, under = _buffers()
    _background(buf, scene, params, table, (dx, dz, t_wall, along_x, ox, oz))
    boxes = object_boxes(scene, pose, params)
    rows = _boxes(buf, under, table, (dx, dz, t_wall), boxes, scene.owners[boxes[4]])
    # R, G, B, owner per pixel; Pillow reads the buffer in place and packs R, G, B.
    image = Image.frombuffer("RGBX", (SIZE, SIZE), buf, "raw", "RGBX", 0, 1)
    frame = np.frombuffer(image.tobytes("raw", "RGB"), dtype=np.uint8).reshape(SIZE, SIZE, 3)
    return frame, _legible(buf[rows], under[rows], len(scene.centres))


def _legible(shown: np.ndarray, under: np.ndarray, objects: int) -> np.ndarray:
    """Per object, its pixels among ``shown`` that differ from ``under`` (what they would show
    without it) by at least :data:`MIN_CONTRAST` levels in some channel."""
    owned = np.flatnonzero(shown >= 1 << 24)
    a, b = shown.ravel()[owned], under.ravel()[owned]
    diff = np.maximum(a.view(np.uint8), b.view(np.uint8))
    diff -= np.minimum(a.view(np.uint8), b.view(np.uint8))
    far = (diff >= MIN_CONTRAST).view("<u4") & 0x010101  # R, G, B; not the owner byte
    return np.bincount(a[far != 0] >> 24, minlength=objects + 1)[1:]


_View = tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.float64, np.float64]
"""Per column ``dx, dz, t_wall, along_x``, then the eye's ``x, z``."""


def _cell(o: np.float64, t: np.ndarray, d: np.ndarray, size: int) -> np.ndarray:
    """Raster index of the points ``o + t * d`` (one coordinate; in cells: ``* RASTER``),
    clipped to ``[0, size)``. Worked in place: a floor's worth of points is a megabyte."""
    a = t * d
    a += o
    a *= RASTER
    return np.clip(a, 0.0, size - 1.0, out=a).astype(np.intp)


def _background(
    buf: np.ndarray, scene: Scene, params: ConditionParams, table: np.ndarray, view: _View
) -> None:
    """Ceiling, walls (their room's colour, shaded by orientation), skirting and floor.

    Per column, rows ``[0, top)`` are ceiling, ``[top, skirt)`` wall, ``[skirt, bottom)``
    skirting and the rest floor (``top <= horizon <= skirt <= bottom``).
    """
    dx, dz, t_wall, along_x, ox, oz = view
    room = scene.room_raster
    nz, nx = room.shape
    top, skirt, bottom = first_row(HORIZON + _K_EDGES / t_wall)
    hx = _cell(ox, t_wall - WALL_BACK, dx, nx)
    hz = _cell(oz, t_wall - WALL_BACK, dz, nz)
    face = np.where(along_x, Z_FACE, X_FACE)
    reach = params.visibility_distance
    weight = fog_weight(t_wall, reach)
    wall = table[(((WALL0 + room[hz, hx]) * 4 + face) << 8) | weight]
    foot = table[((SKIRTING * 4 + face) << 8) | weight]
    sky = table[((CEILING * 4 + Z_FACE) << 8) | fog_weight(_CEILING_DEPTH, reach)]
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
    view: _View,
    first: int,
) -> None:
    """Floor rows ``first`` (counted from the horizon) on, into ``out``: each pixel the
    entry of the raster cell under ``o + depth * d`` at the row's fog. When every ray has
    the same ``dz`` (``dx``), that coordinate's cell is worked out once per row."""
    dx, dz, _, _, ox, oz = view
    floor = scene.floor_raster
    nz, nx = floor.shape
    codes = ((floor * 4 + Z_FACE) << 8).ravel()
    row_fog = fog_weight(_FLOOR_DEPTH[first:], params.visibility_distance)
    fogged = np.count_nonzero(row_fog == FOGGED)  # the far rows: the fog whatever the cell
    out[:fogged] = table[FOGGED]
    out, row_fog = out[fogged:], row_fog[fogged:, None]
    depth = _FLOOR_DEPTH[first + fogged :, None]
    if (dz == dz[0]).all():  # facing north or south: a row's floor lies on one raster row
        z = _cell(oz, depth, dz[0], nz)
        lines = table[codes[z * nx + np.arange(nx)] | row_fog]
        cell = _cell(ox, depth, dx, nx)
    elif (dx == dx[0]).all():  # facing east or west: on one raster column
        x = _cell(ox, depth, dx[0], nx)
        lines = table[codes[np.arange(nz) * nx + x] | row_fog]
        cell = _cell(oz, depth, dz, nz)
    else:
        x = _cell(ox, depth, dx, nx)
        z = _cell(oz, depth, dz, nz)
        np.take(table, codes[z * nx + x] | row_fog, out=out)
        return
    cell += np.arange(0, lines.size, lines.shape[1])[:, None]
    np.take(lines, cell, out=out)


def _boxes(
    buf: np.ndarray,
    under: np.ndarray,
    table: np.ndarray,
    rays: tuple[np.ndarray, np.ndarray, np.ndarray],
    boxes: tuple[np.ndarray, ...],
    owners: np.ndarray,
) -> slice:
    """Paint the boxes back to front, each over the columns it can cover; return the rows
    painted.

    A column's ray is inside a box from ``tn`` to ``tf`` (slab test); it hits the box when
    that lies between the near plane and the wall. The hit column shows rows ``[start,
    end)`` between the box's top and bottom edges, in the underside's code when the box is
    above the eye, else the front face's; then rows ``[start, over)`` again: a box below the
    eye shows its top down to the top edge's row at ``tn``, one above it its front down to
    the bottom edge's row at ``tn``. All (box, column) pairs are computed at once, laid end
    to end; the painting is one masked copy per face and box. Where a run of boxes of one
    object ``o`` (``owners``) takes a pixel over from another object or the room, ``under``
    keeps what that pixel showed: what the frame shows there without ``o``.
    """
    rel, y, lo, hi, label, extra, reach = boxes
    if lo.size == 0:
        return slice(0, 0)
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
    fog = fog_weight(tn, reach[k])
    # A box column wholly in the fog paints the fog colour; before any clear one in its
    # column it paints it over the fog (walls and floor behind it lie deeper): skip it.
    clear = hit & (fog < FOGGED)
    first_clear = np.full(SIZE, lo.size)
    np.minimum.at(first_clear, cols[clear], k[clear])
    hit &= clear | (k > first_clear[cols])
    y0, y1, kind = y[k, 0], y[k, 1], extra[k]
    start = first_row(np.minimum(HORIZON - y1 / tn, HORIZON - y1 / tf))
    end = first_row(np.maximum(HORIZON - y0 / tn, HORIZON - y0 / tf))
    over = np.where(
        kind == 1,
        first_row(HORIZON - y1 / tn),
        np.where(kind == 2, first_row(HORIZON - y0 / tn), start),
    )
    lit = ((label[k] * 4) << 8) | fog
    front = lit + (np.where(near_x > near_z, X_FACE, Z_FACE) << 8)
    first = table[np.where(kind == 2, lit + (BOTTOM_FACE << 8), front)]
    second = table[np.where(kind == 1, lit + (TOP_FACE << 8), front)]
    start = np.where(hit, start, SIZE)
    end = np.where(hit, end, 0)
    # Rows counted from ``start`` and read as unsigned: rows above it wrap to huge values,
    # so ``counted < span`` is ``start <= row < start + span`` in one comparison.
    span = np.maximum(end - start, 0).view(np.uint16)
    over = np.maximum(np.minimum(over, end) - start, 0).view(np.uint16)
    r0, r1 = np.minimum.reduceat(start, offset), np.maximum.reduceat(end, offset)
    drawn = np.flatnonzero(r1 > r0)
    if drawn.size == 0:
        return slice(0, 0)
    painted = np.stack([r0, r1, lo, width, offset, extra])[:, drawn].T.tolist()
    # A run of boxes of one object keeps what it takes over in one copy, not one per box.
    cuts = [0, *(np.flatnonzero(np.diff(owners[drawn])) + 1).tolist(), len(painted)]
    shown = buf.view(np.uint8)[:, 3::4]
    for run in (painted[i:j] for i, j in itertools.pairwise(cuts)):
        ys = slice(min(b[0] for b in run), max(b[1] for b in run))
        xs = slice(min(b[2] for b in run), max(b[2] + b[3] for b in run))
        before = buf[ys, xs].copy()
        for z0, z1, c0, w, at, two in run:
            cut = slice(at, at + w)
            counted = (_ROWS[z0:z1, None] - start[cut]).view(np.uint16)
            region = buf[z0:z1, c0 : c0 + w]
            np.copyto(region, first[cut], where=counted < span[cut])
            if two:
                np.copyto(region, second[cut], where=counted < over[cut])
        # Pixels the run's object took from another object or the room.
        taken = shown[ys, xs] != before.view(np.uint8)[:, 3::4]
        np.copyto(under[ys, xs], before, where=taken)
    return slice(int(r0[drawn].min()), int(r1[drawn].max()))


@functools.lru_cache(maxsize=16)
def _rays(heading: float) -> tuple[np.ndarray, np.ndarray]:
    """Direction ``forward + right * u`` of each column's ray at ``heading`` (shared)."""
    fx, fz = unit(heading)
    rx, rz = right_of(heading)
    return fx + rx * _U, fz + rz * _U


_LOCAL = threading.local()


def _buffers() -> tuple[np.ndarray, np.ndarray]:
    """This thread's scratch frame and the colours under its objects, ``R | G << 8 | B << 16 |
    owner << 24`` little-endian words (a fresh megabyte per frame costs page faults)."""
    bufs: tuple[np.ndarray, np.ndarray] | None = getattr(_LOCAL, "buffers", None)
    if bufs is None:
        bufs = _LOCAL.buffers = (np.empty((SIZE, SIZE), "<u4"), np.empty((SIZE, SIZE), "<u4"))
    return bufs
