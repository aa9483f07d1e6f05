"""The boxes of nearby objects in the first-person frame: which, in which order, where.

Each box is ray-cast only over the image columns it can cover: a conservative column range
from the box's extent in the camera frame (clipped to the near plane, one column of margin
each side), so the per-column slab test runs on a few thousand (box, column) pairs rather
than on every box times all 512 columns; columns outside a box's range cannot hit it (its
rays pass more than a column's angle, ``1 / 256``, away from the box). This module selects
the boxes and orders them back to front (:func:`object_boxes`); the slab test and the
painting, per column, are :func:`pytest_emrd.world._render.render`'s.
"""

from __future__ import annotations

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


def fog_weight(depth: np.ndarray, draw_distance: float, fog: float) -> np.ndarray:
    """Fog weight 0..255 (int64) of surfaces at ``depth``: ``rint(min(1, f * (d / v)^2) *
    255)`` with ``v`` the drawn distance and ``f`` the fog at that distance."""
    ratio = depth / draw_distance
    return np.rint(np.minimum(1.0, fog * ratio * ratio) * 255.0).astype(np.int64)


def first_row(a: np.ndarray) -> np.ndarray:
    """First image row whose pixel centre lies at or below the continuous row ``a``, in
    ``[0, 512]`` (int64)."""
    return np.minimum(np.maximum(np.ceil(a - 0.5), 0.0), float(SIZE)).astype(np.int64)


def _dist2(rects: np.ndarray, x: float, z: float) -> np.ndarray:
    """Squared distance from ``(x, z)`` to the nearest point of each rectangle
    ``x0, z0, x1, z1``."""
    ddx = np.maximum(np.maximum(rects[:, 0] - x, x - rects[:, 2]), 0.0)
    ddz = np.maximum(np.maximum(rects[:, 1] - z, z - rects[:, 3]), 0.0)
    return ddx * ddx + ddz * ddz


def object_boxes(scene: Scene, pose: WorldPose, params: ConditionParams) -> tuple[np.ndarray, ...]:
    """The boxes of nearby objects as :func:`pytest_emrd.world._render.render` paints them,
    back to front.

    A box is kept when its object lies within the drawn distance (to the nearest point of
    its footprint), it shows from the eye's side (or from every side), some footprint corner
    lies past the near plane, the corners are not all beyond one edge of the view wedge, and
    its column range (from the extreme ray slopes ``lateral / forward`` over its corners,
    the forward distance clipped to the near plane, one column of margin) is not empty.
    Kept boxes are ordered by the squared distance to the footprint of the object their
    object stands on (farthest first: an item on a desk takes its desk's), then by their
    bottom (lowest first), then by the squared distance to their own footprint (farthest
    first), ties in scene order.

    Per box: ``(n, 4)`` planes ``x0, z0, x1, z1`` relative to the eye, ``(n, 2)``
    ``focal * (y - eye)`` of its bottom and top, the first and one past the last image
    column its rays can hit, its label, and which extra face shows: 1 the top (a box below
    the eye), 2 the underside (above the eye), 0 neither.
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
    return rel, FOCAL * (p[:, 4:6] - EYE), lo, hi, scene.part_label[sel], extra
