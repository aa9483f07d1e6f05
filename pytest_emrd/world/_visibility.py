"""What the agent sees: the objects its frame shows legibly.

One rule, read off the frame the agent is sent (:func:`~pytest_emrd.world._render.render`):
an object is visible at a step if and only if at least :data:`LEGIBLE_PIXELS` pixels of that
frame show it and differ by at least :data:`~pytest_emrd.world._render.MIN_CONTRAST` levels
in some channel from what the frame would show there without it. What hides it owns the
pixels; fog and darkness take the contrast. Why these constants:
``docs/interpretation/world.md`` ("Visibility"). A visible object's bearing is that of its
centre, clipped to ``[-45, 45]``, its distance to its centre.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np

from pytest_emrd.world._conditions import condition_params
from pytest_emrd.world._geometry import HEADINGS, right_of, unit
from pytest_emrd.world._model import Layout, VisibleObject, WorldPose
from pytest_emrd.world._scene import Scene, scene_of

HALF_FOV = 45.0
LEGIBLE_PIXELS = 150
"""Legible pixels that make an object visible: about a 12 x 12 pixel patch, a chair seen
whole at 4.5 m, a laptop at 3 m."""
STAND_SPACING = 0.75
"""Grid spacing of the standing points that define ``G_base``."""
SPREAD = 8
"""Stride of the order :func:`discoverable_ids` visits standing points in: every part of
the office comes early, and the search stops once every object has been seen."""


def in_view(scene: Scene, pose: WorldPose, legible: np.ndarray) -> tuple[VisibleObject, ...]:
    """The visible objects of a frame drawn from ``pose`` with ``legible`` pixels per object
    (:func:`~pytest_emrd.world._render.render`), as the symbolic modality reports them,
    sorted by id."""
    shown = np.flatnonzero(legible >= LEGIBLE_PIXELS)
    fx, fz = unit(pose.heading)
    rx, rz = right_of(pose.heading)
    cx = scene.centres[shown, 0] - pose.x
    cz = scene.centres[shown, 1] - pose.z
    bearing = np.degrees(np.arctan2(cx * rx + cz * rz, cx * fx + cz * fz))
    bearing = np.clip(bearing, -HALF_FOV, HALF_FOV)
    objs = scene.layout.objects
    out = [
        VisibleObject(
            objs[i].object_id, objs[i].object_type, round(float(b), 1), round(float(d), 2)
        )
        for i, b, d in zip(shown, bearing, np.hypot(cx, cz), strict=True)
    ]
    return tuple(sorted(out, key=lambda v: v.object_id))


def standing_points(scene: Scene) -> np.ndarray:
    """``(M, 2)`` free points: 1 m either side of each doorway, then a grid in every room."""
    pts = []
    for d in scene.layout.doorways:
        nx, nz = (0.0, 1.0) if d.axis == "x" else (1.0, 0.0)
        pts.append(np.array([[d.x + nx, d.z + nz], [d.x - nx, d.z - nz]]))
    for r in scene.layout.rooms:
        xs = np.arange(r.x0 + 0.4, r.x1 - 0.39, STAND_SPACING)
        zs = np.arange(r.z0 + 0.4, r.z1 - 0.39, STAND_SPACING)
        gx, gz = np.meshgrid(xs, zs)
        pts.append(np.stack([gx.ravel(), gz.ravel()], axis=1))
    grid = np.round(np.concatenate(pts), 2)  # centimetre positions, as the world's poses
    return grid[~scene.crowded(grid[:, 0], grid[:, 1])]


@lru_cache(maxsize=256)
def discoverable_ids(layout: Layout) -> tuple[str, ...]:
    """``G_base``: ids visible under the *baseline* condition from some standing point
    (:func:`standing_points`) under one of the four headings, sorted; cached per layout.
    The paper office needs 68 frames."""
    from pytest_emrd.world._render import render, shade_table  # Pillow: only when needed

    scene = scene_of(layout)
    params = condition_params("baseline")
    table = shade_table(scene.colors, params, scene.owners)
    seen = np.zeros(len(layout.objects), dtype=bool)
    points = standing_points(scene)
    order = np.concatenate([np.arange(start, len(points), SPREAD) for start in range(SPREAD)])
    for x, z in points[order]:
        for heading in HEADINGS:
            seen |= render(scene, WorldPose(float(x), float(z), heading), params, table)[1] >= (
                LEGIBLE_PIXELS
            )
        if seen.all():
            break
    return tuple(sorted(layout.objects[i].object_id for i in np.flatnonzero(seen)))
