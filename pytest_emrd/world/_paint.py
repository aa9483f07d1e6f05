"""The boxes of nearby objects in the first-person frame, painted back to front.

Each box is ray-cast only over the image columns it can cover: a conservative column range
from the box's extent in the camera frame (clipped to the near plane, one column of margin
each side), so the per-column slab test runs on a few thousand (box, column) pairs laid end
to end in flat arrays rather than on every box times all 512 columns. Every per-column
quantity is the same element-wise IEEE expression as over the full width, so the codes are
identical; columns outside a box's range cannot hit it (its rays pass more than a column's
angle, ``1 / 256``, away from the box). Each box then paints, over the bounding rectangle of
the columns it hits, its rows ``[start, end)`` in one colour and its first ``over`` rows
again in a second colour (see :func:`object_spans`); the painting itself is
:func:`pytest_emrd.world._kernel.compose`.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from pytest_emrd.world._conditions import ConditionParams
from pytest_emrd.world._geometry import right_of, unit
from pytest_emrd.world._model import WorldPose
from pytest_emrd.world._scene import Scene

SIZE = 512
FOCAL = SIZE / 2
HORIZON = SIZE // 2
EYE = 1.5
NEAR = 0.05

#: Surface orientations: faces across x (east/west), across z (north/south), tops,
#: undersides. A surface's code is ``(label * 4 + face) << 8 | fog``, its colour
#: ``table[code]`` (:func:`pytest_emrd.world._render.shade_table`).
X_FACE, Z_FACE, TOP_FACE, BOTTOM_FACE = 0, 1, 2, 3


def fog(depth: np.ndarray, params: ConditionParams) -> np.ndarray:
    """Fog weight 0..255 of surfaces at ``depth``."""
    ratio = depth / params.visibility_distance
    return np.rint(np.minimum(1.0, params.fog * ratio * ratio) * 255.0).astype(np.int32)


def first_row(a: np.ndarray) -> np.ndarray:
    """First image row whose pixel centre lies at or below the continuous row ``a``, in
    ``[0, 512]`` (int16)."""
    row = np.ceil(a - 0.5)
    np.maximum(row, 0, out=row)
    return np.minimum(row, SIZE, out=row).astype(np.int16)


def length(first: np.ndarray, end: np.ndarray) -> np.ndarray:
    """Rows in ``[first, end)`` per column (0 when empty), as uint16."""
    return np.maximum(end - first, 0).astype(np.uint16)


@dataclass(frozen=True, eq=False)
class _Boxes:
    """Per-scene arrays of every box, gathered once (see :func:`_boxes`)."""

    corner_x: np.ndarray
    """``(P, 4)`` x of the footprint corners."""
    corner_z: np.ndarray
    centre: np.ndarray
    """``(P, 2)`` centre of the box's object."""
    group: np.ndarray
    """``(P, 4)`` footprint of the object the box's object stands on (draw order)."""
    base: np.ndarray
    """``(P,)`` int32 ``label * 4``."""
    always: np.ndarray
    """``(P,)`` whether the box shows from every side."""


@lru_cache(maxsize=32)
def _boxes(scene: Scene) -> _Boxes:
    parts, facing = scene.parts, scene.part_facing
    return _Boxes(
        corner_x=np.ascontiguousarray(parts[:, [0, 0, 2, 2]]),
        corner_z=np.ascontiguousarray(parts[:, [1, 3, 1, 3]]),
        centre=scene.centres[scene.part_object],
        group=scene.rects[scene.support[scene.part_object]],
        base=(scene.part_label * 4).astype(np.int32),
        always=(facing[:, 0] == 0) & (facing[:, 1] == 0),
    )


def _dist2(rects: np.ndarray, pose: WorldPose) -> np.ndarray:
    """Squared distance from the agent to the nearest point of each rectangle."""
    ddx = np.maximum(np.maximum(rects[:, 0] - pose.x, pose.x - rects[:, 2]), 0.0)
    ddz = np.maximum(np.maximum(rects[:, 1] - pose.z, pose.z - rects[:, 3]), 0.0)
    return ddx * ddx + ddz * ddz


def _shown(scene: Scene, pose: WorldPose, params: ConditionParams) -> tuple[np.ndarray, ...]:
    """Boxes of objects within the visibility distance, minus faces turned away and boxes
    wholly outside one edge of the view wedge; and for those the first and one past the
    last image column their rays can hit."""
    boxes = _boxes(scene)
    near = (_dist2(scene.rects, pose) <= params.visibility_distance**2)[scene.part_object]
    nf = scene.part_facing
    side = (pose.x - boxes.centre[:, 0]) * nf[:, 0] + (pose.z - boxes.centre[:, 1]) * nf[:, 1]
    fx, fz = unit(pose.heading)
    rx, rz = right_of(pose.heading)
    cx, cz = boxes.corner_x - pose.x, boxes.corner_z - pose.z
    fwd, lat = cx * fx + cz * fz, cx * rx + cz * rz
    out_of_view = (fwd <= NEAR).all(axis=1) | (lat > fwd).all(axis=1) | (lat < -fwd).all(axis=1)
    sel = np.flatnonzero(near & (boxes.always | (side > nf[:, 2])) & ~out_of_view)
    fwd, lat = fwd[sel], lat[sel]
    # The box's camera-frame bounding rectangle clipped to the near plane: its rays have
    # slopes u = lateral / forward between the extremes at the rectangle's corners.
    f0, f1 = np.maximum(fwd.min(axis=1), NEAR), fwd.max(axis=1)
    l0, l1 = lat.min(axis=1), lat.max(axis=1)
    u0, u1 = np.minimum(l0 / f0, l0 / f1), np.maximum(l1 / f0, l1 / f1)
    lo = np.clip(np.floor(u0 * FOCAL + (FOCAL - 0.5)) - 1, 0, SIZE).astype(np.int64)
    hi = np.clip(np.ceil(u1 * FOCAL + (FOCAL - 0.5)) + 2, 0, SIZE).astype(np.int64)
    wide = hi > lo
    return sel[wide], lo[wide], hi[wide]


Columns = tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]
"""Per (box, column) pair: ``start`` row (int16), ``span`` and ``over`` row counts (uint16),
``first`` and ``second`` codes (int32)."""
_NOTHING = (
    np.zeros((0, 6), dtype=np.int64),
    tuple(np.zeros(0, dtype=t) for t in (np.int16, np.uint16, np.uint16, np.int32, np.int32)),
)


def object_spans(
    scene: Scene,
    pose: WorldPose,
    params: ConditionParams,
    rays: tuple[np.ndarray, np.ndarray, np.ndarray],
) -> tuple[np.ndarray, Columns]:
    """What the boxes of nearby objects paint, back to front: by the distance of the object
    (an item on a desk takes its desk's), then bottom-up, then farther boxes first (nothing
    when no box is in view).

    ``rays`` is ``(dx, dz, t_wall)`` per column. A box shows its front face, its top face
    when below the eye, its underside when above; each column it hits is painted as rows
    ``[start, start + span)`` in code ``first`` (the underside when the box is above the
    eye, else the front face), then its first ``over`` rows again in code ``second``: the
    top face down to where the front begins, or the front face down to where the underside
    begins. Returned as ``(rects, columns)`` for :func:`pytest_emrd.world._kernel.compose`:
    ``rects`` rows ``r0, r1, c0, c1, at, two`` (int64) in drawing order, the rows and
    columns a box can touch, where its entries start in ``columns`` and whether it has a
    second face.
    """
    sel, lo, hi = _shown(scene, pose, params)
    if sel.size == 0:
        return _NOTHING
    dx, dz, t_wall = rays
    width = hi - lo
    offset = np.cumsum(width) - width
    k = np.repeat(np.arange(sel.size), width)
    cols = np.arange(int(offset[-1] + width[-1])) + np.repeat(lo - offset, width)
    p = scene.parts[sel]
    # Where each column's ray crosses the planes x0, z0, x1, z1 of the box (slab test).
    rel = np.take(p[:, :4] - (pose.x, pose.z, pose.x, pose.z), k, axis=0)
    slab = rel / np.take(np.stack((dx, dz, dx, dz), 1), cols, axis=0)
    near, far = np.minimum(slab[:, :2], slab[:, 2:]), np.maximum(slab[:, :2], slab[:, 2:])
    tn, tf = np.maximum(near[:, 0], near[:, 1]), np.minimum(far[:, 0], far[:, 1])
    hit = (tn < tf) & (tn > NEAR) & (tn < np.take(t_wall, cols))
    tn, tf = np.where(hit, tn, 1.0), np.where(hit, tf, 1.0)
    # Rows of the bottom (y0) and top (y1) edges at the near and the far hit.
    y = np.take(FOCAL * (p[:, 4:6] - EYE), k, axis=0)
    at_near, at_far = HORIZON - y / tn[:, None], HORIZON - y / tf[:, None]
    edges = np.empty((k.size, 4))
    np.minimum(at_near[:, 1], at_far[:, 1], out=edges[:, 0])
    np.maximum(at_near[:, 0], at_far[:, 0], out=edges[:, 1])
    edges[:, 2:] = at_near
    rows = first_row(edges)
    start = np.where(hit, rows[:, 0], np.int16(SIZE))
    end = np.where(hit, rows[:, 1], np.int16(0))
    has_top, has_bottom = p[:, 5] < EYE, p[:, 4] > EYE
    top_k, bottom_k = np.take(has_top, k), np.take(has_bottom, k)
    over_end = np.where(top_k, rows[:, 3], np.where(bottom_k, rows[:, 2], start))
    span = length(start, end)
    over = length(start, np.minimum(over_end, end))
    # ((label * 4 + face) << 8) | fog, as (label * 4 << 8 | fog) + (face << 8).
    lit = np.take(_boxes(scene).base[sel] << 8, k) | fog(tn, params)
    front = lit + np.where(near[:, 0] > near[:, 1], np.int32(X_FACE << 8), np.int32(Z_FACE << 8))
    first = np.where(bottom_k, lit + (BOTTOM_FACE << 8), front)
    second = np.where(top_k, lit + (TOP_FACE << 8), front)
    c0 = np.minimum.reduceat(np.where(hit, cols, SIZE), offset)
    c1 = np.maximum.reduceat(np.where(hit, cols, -1), offset) + 1
    rects = np.stack(
        (
            np.minimum.reduceat(start, offset),
            np.maximum.reduceat(end, offset),
            c0,
            c1,
            offset + c0 - lo,
            has_top | has_bottom,
        ),
        axis=1,
    ).astype(np.int64)
    drawn = np.flatnonzero(c1 > c0)
    order = drawn[_draw_order(scene, pose, sel[drawn])]
    return rects[order], (start, span, over, first, second)


def _draw_order(scene: Scene, pose: WorldPose, sel: np.ndarray) -> np.ndarray:
    """Indices into ``sel`` back to front: by the distance of the object (an item on a desk
    takes its desk's), then bottom-up, then farther boxes first."""
    parts = scene.parts[sel]
    group = _dist2(_boxes(scene).group[sel], pose)
    return np.lexsort((-_dist2(parts[:, :4], pose), parts[:, 4], -group))
