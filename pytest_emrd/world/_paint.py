"""The boxes of nearby objects in the first-person frame: which, in which order, where.

Each box is ray-cast only over the image columns it can cover: a conservative column range
from the box's extent in the camera frame (clipped to the near plane, one column of margin
each side), so the per-column slab test runs on a few thousand (box, column) pairs rather
than on every box times all 512 columns; columns outside a box's range cannot hit it (its
rays pass more than a column's angle, ``1 / 256``, away from the box). This module selects
the boxes and orders them back to front (numpy, per box); the slab test and the painting,
per column, are :func:`pytest_emrd.world._kernel.compose`'s.
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


def object_boxes(scene: Scene, pose: WorldPose, params: ConditionParams) -> tuple[np.ndarray, ...]:
    """The boxes of nearby objects as :func:`pytest_emrd.world._kernel.compose` paints
    them, back to front: by the distance of the object (an item on a desk takes its desk's),
    then bottom-up, then farther boxes first.

    Per box: ``(n, 4)`` planes ``x0, z0, x1, z1`` relative to the eye, ``(n, 2)``
    ``focal * (y - eye)`` of its bottom and top, the first and one past the last image
    column its rays can hit, its label, and which extra face shows: 1 the top (a box below
    the eye), 2 the underside (above the eye), 0 neither.
    """
    sel, lo, hi = _shown(scene, pose, params)
    order = _draw_order(scene, pose, sel)
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


def _draw_order(scene: Scene, pose: WorldPose, sel: np.ndarray) -> np.ndarray:
    """Indices into ``sel`` back to front: by the distance of the object (an item on a desk
    takes its desk's), then bottom-up, then farther boxes first."""
    parts = scene.parts[sel]
    group = _dist2(_boxes(scene).group[sel], pose)
    return np.lexsort((-_dist2(parts[:, :4], pose), parts[:, 4], -group))
