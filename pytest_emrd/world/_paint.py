"""The boxes of nearby objects in the first-person frame: which, in which order, where.

Each box is ray-cast only over the image columns it can cover: a conservative column range
from the box's extent in the camera frame (clipped to the near plane, one column of margin
each side), so the per-column slab test runs on a few thousand (box, column) pairs rather
than on every box times all 512 columns; columns outside a box's range cannot hit it (its
rays pass more than a column's angle, ``1 / 256``, away from the box). This module hands
the scene to :func:`pytest_emrd.world._kernel.boxes_in_view`, which selects the boxes and
orders them back to front; the slab test and the painting, per column, are
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
_CAMERA = (NEAR, float(FOCAL), float(SIZE), EYE)

#: Surface orientations: faces across x (east/west), across z (north/south), tops,
#: undersides. A surface's code is ``(label * 4 + face) << 8 | fog``, its colour
#: ``table[code]`` (:func:`pytest_emrd.world._render.shade_table`).
X_FACE, Z_FACE, TOP_FACE, BOTTOM_FACE = 0, 1, 2, 3


def object_boxes(scene: Scene, pose: WorldPose, params: ConditionParams) -> tuple[np.ndarray, ...]:
    """The boxes of nearby objects as :func:`pytest_emrd.world._kernel.compose` paints
    them, back to front: by the distance of the object (an item on a desk takes its desk's),
    then bottom-up, then farther boxes first (compiled:
    :func:`pytest_emrd.world._kernel.boxes_in_view`, which says which boxes are kept).

    Per box: ``(n, 4)`` planes ``x0, z0, x1, z1`` relative to the eye, ``(n, 2)``
    ``focal * (y - eye)`` of its bottom and top, the first and one past the last image
    column its rays can hit, its label, and which extra face shows: 1 the top (a box below
    the eye), 2 the underside (above the eye), 0 neither.
    """
    from pytest_emrd.world._kernel import boxes_in_view  # numba: loaded with the first frame

    fx, fz = unit(pose.heading)
    rx, rz = right_of(pose.heading)
    eye = (float(pose.x), float(pose.z), float(fx), float(fz), float(rx), float(rz))
    arrays = (scene.parts, scene.part_object, scene.part_facing, scene.rects, scene.centres)
    n = len(scene.parts)
    out = (np.empty((n, 4)), np.empty((n, 2)), *(np.empty(n, np.int64) for _ in range(4)))
    vis2 = params.draw_distance**2
    count = boxes_in_view((*arrays, scene.support, scene.part_label), eye, vis2, _CAMERA, out)
    return tuple(a[:count] for a in out)
