"""The boxes of nearby objects in the first-person frame: which, in which order, where.

Each box is ray-cast only over the image columns it can cover: a conservative column range
from the box's extent in the camera frame (clipped to the near plane, one column of margin
each side), so the per-column slab test runs on a few thousand (box, column) pairs rather
than on every box times all 512 columns; columns outside a box's range cannot hit it (its
rays pass more than a column's angle, ``1 / 256``, away from the box). This module selects
the boxes (compiled, :func:`pytest_emrd.world._kernel.shown_boxes`) and orders them back to
front (numpy); the slab test and the painting, per column, are
:func:`pytest_emrd.world._kernel.compose`'s.
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
_CAMERA = (NEAR, float(FOCAL), float(SIZE))

#: Surface orientations: faces across x (east/west), across z (north/south), tops,
#: undersides. A surface's code is ``(label * 4 + face) << 8 | fog``, its colour
#: ``table[code]`` (:func:`pytest_emrd.world._render.shade_table`).
X_FACE, Z_FACE, TOP_FACE, BOTTOM_FACE = 0, 1, 2, 3


def _shown(scene: Scene, pose: WorldPose, params: ConditionParams) -> tuple[np.ndarray, ...]:
    """Boxes of objects within the visibility distance, minus faces turned away and boxes
    wholly outside one edge of the view wedge; for those the first and one past the last
    image column their rays can hit, and their draw-order keys: the squared distance to the
    footprint of the object their object stands on and to their own footprint (compiled:
    :func:`pytest_emrd.world._kernel.shown_boxes`, which says how the columns are bounded)."""
    from pytest_emrd.world._kernel import shown_boxes  # numba: loaded with the first frame

    fx, fz = unit(pose.heading)
    rx, rz = right_of(pose.heading)
    eye = (float(pose.x), float(pose.z), float(fx), float(fz), float(rx), float(rz))
    arrays = (scene.parts, scene.part_object, scene.part_facing, scene.rects, scene.centres)
    n = len(scene.parts)
    out = (np.empty(n, np.int64), np.empty(n, np.int64), np.empty(n, np.int64))
    keys = (np.empty(n), np.empty(n))
    vis2 = params.visibility_distance**2
    count = shown_boxes((*arrays, scene.support), eye, vis2, _CAMERA, (*out, *keys))
    return tuple(a[:count] for a in (*out, *keys))


def object_boxes(scene: Scene, pose: WorldPose, params: ConditionParams) -> tuple[np.ndarray, ...]:
    """The boxes of nearby objects as :func:`pytest_emrd.world._kernel.compose` paints
    them, back to front: by the distance of the object (an item on a desk takes its desk's),
    then bottom-up, then farther boxes first.

    Per box: ``(n, 4)`` planes ``x0, z0, x1, z1`` relative to the eye, ``(n, 2)``
    ``focal * (y - eye)`` of its bottom and top, the first and one past the last image
    column its rays can hit, its label, and which extra face shows: 1 the top (a box below
    the eye), 2 the underside (above the eye), 0 neither.
    """
    sel, lo, hi, group, own = _shown(scene, pose, params)
    order = np.lexsort((-own, scene.parts[sel, 4], -group))
    sel, lo, hi = sel[order], lo[order], hi[order]
    p = scene.parts[sel]
    extra = np.where(p[:, 5] < EYE, 1, np.where(p[:, 4] > EYE, 2, 0))
    return (
        p[:, :4] - (pose.x, pose.z, pose.x, pose.z),
        FOCAL * (p[:, 4:6] - EYE),
        lo,
        hi,
        scene.part_label[sel],
        extra,
    )
