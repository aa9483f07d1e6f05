"""The renderer's per-column and per-pixel stages, compiled with numba.

:mod:`pytest_emrd.world._render` hands over each column's ray and wall hit and the boxes in
view, back to front (numpy); this kernel works out, per column, the rows where the wall,
the skirting and each box begin and end and the shade-table code each shows, fills a
``uint32`` buffer (ceiling, walls, skirting, the floor's raster look-up, then the boxes)
and unpacks it into the frame's ``R, G, B`` bytes.

Bit identity with the numpy renderer the frame digests were recorded from: every
floating-point value is computed with the same exactly rounded IEEE operations (``+ - * /``,
comparisons, ``ceil``, ``rint``, truncating casts), on the same operands, in the same
order. numba without ``fastmath`` neither reorders them nor contracts a multiply and an add
into an FMA; ``error_model="numpy"`` makes a division by zero give ``inf`` as numpy does.
No transcendental function is used; no arithmetic touches a colour. A surface's code is
``(label * 4 + face) << 8 | fog`` (:func:`pytest_emrd.world._render.shade_table`).

numba is imported with this module, on the first frame (:func:`pytest_emrd.world._render.render`
imports it lazily), so importing the package, loading the plugin or collecting tests never
loads it. Compiled code is cached on disk (``cache=True``: ``__pycache__`` next to this
file, else the user's cache directory); processes compiling at once each write under a
unique name and rename into place. The cache notices changes to this file only, so every
constant comes in as an argument.
"""

from __future__ import annotations

import numpy as np
from numba import njit

View = tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, float, float]
"""Per column the ray ``dx, dz``, the wall hit ``t_wall`` and whether that wall runs along
x; the eye ``ox, oz``."""
Rooms = tuple[np.ndarray, np.ndarray, float]
"""``(nz, nx)`` raster of floor labels (alternate tiles darker) and of room indices, and its
cells per metre."""
Boxes = tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]
"""Back to front: ``(n, 4)`` box planes ``x0, z0, x1, z1`` relative to the eye, ``(n, 2)``
``focal * (y - eye)`` of the bottom and top, the first and one past the last column the box
can cover, its label, and which extra face shows (1 top, 2 underside, 0 none)."""
Camera = tuple[np.ndarray, np.ndarray, float, float, float, float, float]
"""Depth of each ceiling row and of each floor row; ``focal * (wall height - eye)``,
``focal * (eye - skirting height)``, ``focal * eye``; the near plane; how far before the wall
its room is looked up."""
Labels = tuple[int, int, int, int, int, int, int]
"""Labels of the ceiling, the skirting and the first room's wall; the faces across x, across
z, tops and undersides (:data:`pytest_emrd.world._paint.X_FACE` ...)."""
Fog = tuple[float, float]
"""The condition's visibility distance and fog at that distance."""

_JIT = {"cache": True, "nogil": True, "error_model": "numpy"}


@njit(**_JIT)
def fog_weight(depth: float, fog: Fog) -> int:
    """Fog weight 0..255 of a surface at ``depth``: ``rint(min(1, f * (d / v)^2) * 255)``."""
    ratio = depth / fog[0]
    return np.int64(np.rint(min(1.0, fog[1] * ratio * ratio) * 255.0))


@njit(**_JIT)
def first_row(a: float, size: int) -> int:
    """First image row whose pixel centre lies at or below the continuous row ``a``, in
    ``[0, size]``."""
    return np.int64(min(max(np.ceil(a - 0.5), 0.0), float(size)))


@njit(**_JIT)
def _cell(a: float, size: int) -> int:
    """Raster index of a coordinate already scaled to cells, clipped to ``[0, size)``
    (clipping first makes the truncation a floor)."""
    return np.int64(min(max(a, 0.0), size - 1.0))


@njit(**_JIT)
def compose(
    frame: np.ndarray,
    buf: np.ndarray,
    table: np.ndarray,
    view: View,
    rooms: Rooms,
    boxes: Boxes,
    camera: Camera,
    labels: Labels,
    fog: Fog,
) -> None:
    """Draw into ``frame`` (``(S, S, 3)`` uint8) through ``buf``, uint32 scratch of ``S``
    rows of at least ``S`` entries (rows padded by a cache line keep the column-wise box
    spans from evicting each other from the L1 cache: a 2 KiB stride maps a whole column
    onto two cache sets). ``table``: entries ``R | G << 8 | B << 16`` by code."""
    _background(buf, table, view, rooms, camera, labels, fog)
    _boxes(buf, table, view, boxes, camera, labels, fog)
    for r in range(frame.shape[0]):
        row, out = buf[r], frame[r].reshape(-1)
        for c in range(frame.shape[1]):
            entry = row[c]
            out[3 * c] = entry & 0xFF
            out[3 * c + 1] = (entry >> 8) & 0xFF
            out[3 * c + 2] = (entry >> 16) & 0xFF


@njit(**_JIT)
def _constant(a: np.ndarray) -> bool:
    """Whether every entry of ``a`` equals the first (``0.0 == -0.0``: either gives the same
    raster cell, ``o + depth * 0``)."""
    return bool((a == a[0]).all())


@njit(**_JIT)
def _background(
    buf: np.ndarray,
    table: np.ndarray,
    view: View,
    rooms: Rooms,
    camera: Camera,
    labels: Labels,
    fog: Fog,
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
    floor, room, scale = rooms
    ceiling_depth, floor_depth, k_top, k_skirt, k_bottom, _, back = camera
    ceiling, skirting, wall0, x_face, z_face = labels[:5]
    horizon, width = ceiling_depth.size, t_wall.size
    size = buf.shape[0]
    nz, nx = room.shape
    top = np.empty(width, np.int64)
    skirt, bottom = np.empty_like(top), np.empty_like(top)
    wall = np.empty(width, np.uint32)
    foot = np.empty_like(wall)
    for c in range(width):
        t = t_wall[c]
        top[c] = first_row(horizon - k_top / t, size)
        bottom[c] = first_row(horizon + k_bottom / t, size)
        skirt[c] = first_row(horizon + k_skirt / t, size)
        hx = _cell((ox + (t - back) * dx[c]) * scale, nx)
        hz = _cell((oz + (t - back) * dz[c]) * scale, nz)
        face = z_face if along_x[c] else x_face
        weight = fog_weight(t, fog)
        wall[c] = table[(((wall0 + room[hz, hx]) * 4 + face) << 8) | weight]
        foot[c] = table[((skirting * 4 + face) << 8) | weight]
    for r in range(horizon):
        sky = table[((ceiling * 4 + z_face) << 8) | fog_weight(ceiling_depth[r], fog)]
        for c in range(width):
            buf[r, c] = sky if r < top[c] else wall[c]
    z_fixed, x_fixed = _constant(dz), _constant(dx)
    line = np.empty(max(nx, nz), np.uint32)
    for r in range(horizon, size):
        d, weight = floor_depth[r - horizon], fog_weight(floor_depth[r - horizon], fog)
        if z_fixed:  # facing north or south: the row's floor lies on one raster row
            z = _cell((d * dz[0] + oz) * scale, nz)
            for x in range(nx):
                line[x] = table[((floor[z, x] * 4 + z_face) << 8) | weight]
        elif x_fixed:  # facing east or west: on one raster column
            x = _cell((d * dx[0] + ox) * scale, nx)
            for z in range(nz):
                line[z] = table[((floor[z, x] * 4 + z_face) << 8) | weight]
        for c in range(width):
            if r < skirt[c]:
                buf[r, c] = wall[c]
            elif r < bottom[c]:
                buf[r, c] = foot[c]
            elif z_fixed:
                buf[r, c] = line[_cell((d * dx[c] + ox) * scale, nx)]
            elif x_fixed:
                buf[r, c] = line[_cell((d * dz[c] + oz) * scale, nz)]
            else:
                x = _cell((d * dx[c] + ox) * scale, nx)
                z = _cell((d * dz[c] + oz) * scale, nz)
                buf[r, c] = table[((floor[z, x] * 4 + z_face) << 8) | weight]


@njit(**_JIT)
def _boxes(
    buf: np.ndarray,
    table: np.ndarray,
    view: View,
    boxes: Boxes,
    camera: Camera,
    labels: Labels,
    fog: Fog,
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
    """
    dx, dz, t_wall = view[0], view[1], view[2]
    rel, y, lo, hi, label, extra = boxes
    x_face, z_face, top_face, bottom_face = labels[3:]
    near_plane = camera[5]
    horizon, size = float(camera[0].size), buf.shape[0]
    for b in range(lo.size):
        for c in range(lo[b], hi[b]):
            x0, x1 = rel[b, 0] / dx[c], rel[b, 2] / dx[c]
            z0, z1 = rel[b, 1] / dz[c], rel[b, 3] / dz[c]
            near_x, near_z = np.minimum(x0, x1), np.minimum(z0, z1)
            tn = np.maximum(near_x, near_z)
            tf = np.minimum(np.maximum(x0, x1), np.maximum(z0, z1))
            if not (tn < tf and tn > near_plane and tn < t_wall[c]):
                continue
            start = first_row(np.minimum(horizon - y[b, 1] / tn, horizon - y[b, 1] / tf), size)
            end = first_row(np.maximum(horizon - y[b, 0] / tn, horizon - y[b, 0] / tf), size)
            lit = (label[b] * 4) << 8 | fog_weight(tn, fog)
            front = lit + ((x_face if near_x > near_z else z_face) << 8)
            if extra[b] == 1:
                first, second = front, lit + (top_face << 8)
                over = first_row(horizon - y[b, 1] / tn, size)
            elif extra[b] == 2:
                first, second = lit + (bottom_face << 8), front
                over = first_row(horizon - y[b, 0] / tn, size)
            else:
                first, second, over = front, front, start
            entry = table[first]
            for r in range(start, end):
                buf[r, c] = entry
            entry = table[second]
            for r in range(start, min(over, end)):
                buf[r, c] = entry


@njit(**_JIT)
def _dist2(rect: np.ndarray, px: float, pz: float) -> float:
    """Squared distance from ``(px, pz)`` to the nearest point of ``rect`` ``x0, z0, x1, z1``."""
    ddx = max(max(rect[0] - px, px - rect[2]), 0.0)
    ddz = max(max(rect[1] - pz, pz - rect[3]), 0.0)
    return ddx * ddx + ddz * ddz


@njit(**_JIT)
def boxes_in_view(
    scene: tuple[np.ndarray, ...],
    eye: tuple[float, float, float, float, float, float],
    visibility2: float,
    camera: tuple[float, float, float, float],
    out: tuple[np.ndarray, ...],
) -> int:
    """The boxes :func:`compose` paints (:func:`pytest_emrd.world._paint.object_boxes`), back
    to front, into ``out[:][:count]``; returns ``count``.

    ``scene``: the scene's ``parts``, ``part_object``, ``part_facing``, object ``rects``,
    ``centres``, ``support`` and ``part_label``; ``eye``: position ``x, z``, forward
    ``fx, fz``, right ``rx, rz``; ``camera``: the near plane, the focal length, the image
    size and the eye height; ``out``: the arrays :func:`compose` takes as ``boxes``. A box is
    kept when its object lies within ``visibility2`` squared metres, it shows from the eye's
    side (or from every side), some footprint corner lies past the near plane and the
    corners are not all beyond one edge of the view wedge, and its column range (from the
    extreme ray slopes ``lateral / forward`` over its corners, the forward distance clipped
    to the near plane, one column of margin) is not empty. Kept boxes are
    ordered by the squared distance to the footprint of the object their object stands on
    (farthest first), then by their bottom (lowest first), then by the squared distance to
    their own footprint (farthest first), ties in scene order.
    """
    parts, part_object, facing, rects, centres, support, part_label = scene
    px, pz, fx, fz, rx, rz = eye
    near_plane, focal, size, eye_y = camera
    rel, y, lo, hi, label, extra = out
    n = parts.shape[0]
    sel, first, last = np.empty(n, np.int64), np.empty(n, np.int64), np.empty(n, np.int64)
    group, own = np.empty(n), np.empty(n)
    count = 0
    for p in range(n):
        obj = part_object[p]
        if not _dist2(rects[obj], px, pz) <= visibility2:
            continue
        always = facing[p, 0] == 0 and facing[p, 1] == 0
        side = (px - centres[obj, 0]) * facing[p, 0] + (pz - centres[obj, 1]) * facing[p, 1]
        if not (always or side > facing[p, 2]):
            continue
        f_lo, f_hi, l_lo, l_hi = np.inf, -np.inf, np.inf, -np.inf
        behind, right, left = True, True, True
        for k in range(4):
            cx = parts[p, 0 if k < 2 else 2] - px
            cz = parts[p, 1 if k % 2 == 0 else 3] - pz
            fwd, lat = cx * fx + cz * fz, cx * rx + cz * rz
            behind &= fwd <= near_plane
            right &= lat > fwd
            left &= lat < -fwd
            f_lo, f_hi = min(f_lo, fwd), max(f_hi, fwd)
            l_lo, l_hi = min(l_lo, lat), max(l_hi, lat)
        if behind or right or left:
            continue
        f_lo = max(f_lo, near_plane)
        u0 = min(l_lo / f_lo, l_lo / f_hi)
        u1 = max(l_hi / f_lo, l_hi / f_hi)
        col0 = min(max(np.floor(u0 * focal + (focal - 0.5)) - 1.0, 0.0), size)
        col1 = min(max(np.ceil(u1 * focal + (focal - 0.5)) + 2.0, 0.0), size)
        if not col1 > col0:
            continue
        sel[count], first[count], last[count] = p, np.int64(col0), np.int64(col1)
        group[count] = -_dist2(rects[support[obj]], px, pz)
        own[count] = -_dist2(parts[p], px, pz)
        count += 1
    order = np.argsort(own[:count], kind="mergesort")  # stable sorts, last key first
    bottom = np.empty(count)
    for k in range(count):
        bottom[k] = parts[sel[order[k]], 4]
    order = order[np.argsort(bottom, kind="mergesort")]
    order = order[np.argsort(group[:count][order], kind="mergesort")]
    for k in range(count):
        p = sel[order[k]]
        rel[k, 0], rel[k, 1] = parts[p, 0] - px, parts[p, 1] - pz
        rel[k, 2], rel[k, 3] = parts[p, 2] - px, parts[p, 3] - pz
        y[k, 0], y[k, 1] = focal * (parts[p, 4] - eye_y), focal * (parts[p, 5] - eye_y)
        lo[k], hi[k], label[k] = first[order[k]], last[order[k]], part_label[p]
        extra[k] = 1 if parts[p, 5] < eye_y else 2 if parts[p, 4] > eye_y else 0
    return count


@njit(**_JIT)
def shade(
    colors: np.ndarray, light: np.ndarray, keep: np.ndarray, haze: np.ndarray, out: np.ndarray
) -> None:
    """Fill ``out`` (``L * F * W`` uint32) with the shade table of
    :func:`pytest_emrd.world._render.shade_table`: entry ``(l, f, w)`` packs channels
    ``rint(colors[l, ch] * light[f] * keep[w] + haze[w, ch])`` clipped to ``0..255`` as
    ``R | G << 8 | B << 16`` (``keep``: the share of the surface at fog weight ``w``,
    ``haze``: the fog's)."""
    faces, weights = light.size, keep.size
    for label in range(colors.shape[0]):
        for face in range(faces):
            base = (label * faces + face) * weights
            for w in range(weights):
                entry = np.uint32(0)
                for ch in range(3):
                    mix = colors[label, ch] * light[face] * keep[w] + haze[w, ch]
                    entry |= np.uint32(min(max(np.rint(mix), 0.0), 255.0)) << (8 * ch)
                out[base + w] = entry
