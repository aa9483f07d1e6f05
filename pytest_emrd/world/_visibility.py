"""What the agent sees: field of view, distance limit and wall occlusion.

An object is visible from a pose when at least one of its sample points (centre, edge
midpoints and corners of its footprint; points along the gap for a doorway) is

* inside the 90 degree field of view (``|lateral| <= forward``),
* no farther than the condition's visibility distance, and
* not hidden by a wall: the segment from the agent to the point crosses no wall segment
  (doorway gaps are open, so rooms are seen through doorways, never through walls).

Furniture does not occlude in this test. A visible object's bearing is that of its centre,
clipped to the field of view (``[-45, 45]``, negative to the left), and its distance is to
its centre.
"""

from __future__ import annotations

import threading
from dataclasses import dataclass
from functools import cached_property, lru_cache
from weakref import WeakKeyDictionary

import numpy as np

from pytest_emrd.errors import ConfigError
from pytest_emrd.world._conditions import condition_params
from pytest_emrd.world._geometry import right_of, unit
from pytest_emrd.world._model import Layout, VisibleObject, WorldObject, WorldPose
from pytest_emrd.world._scene import Scene, scene_of

HALF_FOV = 45.0
STAND_SPACING = 0.75
"""Grid spacing of the standing points that define ``G_base``."""


@dataclass(frozen=True, eq=False)
class Sight:
    """Visibility of every object of a scene from one pose (read-only arrays)."""

    mask: np.ndarray
    """``(N,)`` bool."""
    bearing: np.ndarray
    distance: np.ndarray
    objects: tuple[WorldObject, ...]
    """The scene's objects, in the arrays' order."""

    @cached_property
    def visible(self) -> tuple[VisibleObject, ...]:
        """The visible objects as the symbolic modality reports them, sorted by id."""
        out = [
            VisibleObject(
                object_id=self.objects[i].object_id,
                object_type=self.objects[i].object_type,
                bearing=round(float(self.bearing[i]), 1),
                distance=round(float(self.distance[i]), 2),
            )
            for i in np.flatnonzero(self.mask)
        ]
        return tuple(sorted(out, key=lambda v: v.object_id))

    def listing(self, scene: Scene) -> tuple[VisibleObject, ...]:
        """:attr:`visible`; ``scene`` must be the scene the sight was taken in."""
        if scene.layout.objects is not self.objects:
            raise ConfigError(
                f"listing(scene) of a sight taken in another scene (layout seed "
                f"{scene.layout.seed}); pass the scene given to sight(...)."
            )
        return self.visible


SIGHT_MEMO = 512
"""Sights kept per scene (oldest dropped first): agents come back to the same poses, within
an episode and across the episodes of one office."""
_SIGHTS: WeakKeyDictionary[Scene, dict[tuple[WorldPose, float], Sight]] = WeakKeyDictionary()
_LOCK = threading.Lock()


def sight(scene: Scene, pose: WorldPose, visibility: float) -> Sight:
    """Which objects of ``scene`` are visible from ``pose`` within ``visibility`` metres
    (the sample points' test is compiled: :func:`pytest_emrd.world._sightlines.sight_mask`).
    The last :data:`SIGHT_MEMO` sights of each scene are kept and returned again."""
    key = (pose, visibility)
    with _LOCK:
        memo = _SIGHTS.setdefault(scene, {})
        seen = memo.get(key)
    if seen is None:
        seen = _sight(scene, pose, visibility)
        with _LOCK:
            memo[key] = seen
            while len(memo) > SIGHT_MEMO:
                del memo[next(iter(memo))]
    return seen


def _sight(scene: Scene, pose: WorldPose, visibility: float) -> Sight:
    from pytest_emrd.world._sightlines import sight_mask  # numba: loaded on first use

    fx, fz = unit(pose.heading)
    rx, rz = right_of(pose.heading)
    mask = np.empty(len(scene.centres), dtype=bool)
    frame = (float(pose.x), float(pose.z), float(fx), float(fz), float(rx), float(rz))
    walls = scene.walls
    sight_mask(scene.samples, frame, visibility * visibility, walls.along_x, walls.along_z, mask)
    cx = scene.centres[:, 0] - pose.x
    cz = scene.centres[:, 1] - pose.z
    bearing = np.degrees(np.arctan2(cx * rx + cz * rz, cx * fx + cz * fz))
    arrays = (mask, np.clip(bearing, -HALF_FOV, HALF_FOV), np.hypot(cx, cz))
    for a in arrays:
        a.setflags(write=False)  # shared by every caller of the memo
    return Sight(*arrays, scene.layout.objects)


def standing_points(scene: Scene) -> np.ndarray:
    """``(M, 2)`` free points on a grid in every room, plus 1 m either side of each doorway."""
    pts = []
    for x0, z0, x1, z1 in scene.rooms:
        xs = np.arange(x0 + 0.4, x1 - 0.39, STAND_SPACING)
        zs = np.arange(z0 + 0.4, z1 - 0.39, STAND_SPACING)
        gx, gz = np.meshgrid(xs, zs)
        pts.append(np.stack([gx.ravel(), gz.ravel()], axis=1))
    for d in scene.layout.doorways:
        nx, nz = (0.0, 1.0) if d.axis == "x" else (1.0, 0.0)
        pts.append(np.array([[d.x + nx, d.z + nz], [d.x - nx, d.z - nz]]))
    grid = np.concatenate(pts)
    return grid[~scene.crowded(grid[:, 0], grid[:, 1])]


@lru_cache(maxsize=256)
def discoverable_ids(layout: Layout) -> tuple[str, ...]:
    """``G_base``: ids visible under the *baseline* condition from some standing point.

    Standing points are a 0.75 m grid of free points in every room plus the points 1 m
    either side of each doorway; from each, the four cardinal headings together cover
    every direction, so an object counts when one of its sample points lies within the
    baseline visibility distance with no wall in between. Sorted; cached per layout.
    """
    scene = scene_of(layout)
    vis = condition_params("baseline").visibility_distance
    stand = standing_points(scene)
    pts = scene.samples.reshape(-1, 2)
    dx = pts[None, :, 0] - stand[:, None, 0]
    dz = pts[None, :, 1] - stand[:, None, 1]
    near = dx * dx + dz * dz <= vis * vis
    si, pi = np.nonzero(near)
    clear = ~scene.walls.blocks(stand[si, 0], stand[si, 1], pts[pi, 0], pts[pi, 1])
    seen = np.zeros(len(pts), dtype=bool)
    seen[pi[clear]] = True
    per_object = seen.reshape(scene.samples.shape[:2]).any(axis=1)
    return tuple(sorted(layout.objects[i].object_id for i in np.flatnonzero(per_object)))
