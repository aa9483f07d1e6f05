"""What the agent sees: field of view, distance limit, walls and furniture occlude.

An object is visible from a pose when one of its sample points is inside the 90 degree field
of view (``|lateral| <= forward``), within the condition's visibility distance, and in the
line of sight (:func:`in_line_of_sight`; why: ``docs/interpretation/world.md``). A visible
object's bearing is that of its centre, clipped to ``[-45, 45]``, its distance to its centre.
"""

from __future__ import annotations

import threading
from dataclasses import dataclass
from functools import cached_property, lru_cache

import numpy as np

from pytest_emrd._bounded import remember
from pytest_emrd.errors import ConfigError
from pytest_emrd.world._conditions import condition_params
from pytest_emrd.world._geometry import right_of, unit
from pytest_emrd.world._model import Layout, VisibleObject, WorldObject, WorldPose
from pytest_emrd.world._scene import Scene, scene_of

HALF_FOV = 45.0
EYE = 1.5
"""Eye height in metres (the camera's, :data:`pytest_emrd.world._render.EYE`)."""
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
        rows = zip(self.objects, self.bearing, self.distance, self.mask, strict=True)
        out = [
            VisibleObject(o.object_id, o.object_type, round(float(b), 1), round(float(d), 2))
            for o, b, d, shown in rows
            if shown
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
"""Sights kept per scene (oldest dropped first): agents come back to the same poses."""
_LOCK = threading.Lock()


def sight(
    scene: Scene, pose: WorldPose, visibility: float, landmarks: float | None = None
) -> Sight:
    """Which objects of ``scene`` are visible from ``pose``: objects within ``visibility``
    metres, landmarks (doorways, the exit) within ``landmarks`` metres (default: the same).
    The last :data:`SIGHT_MEMO` sights of each scene are kept and returned again."""
    reach = visibility if landmarks is None else landmarks
    key = (pose, visibility, reach)
    with _LOCK:
        seen = scene.sights.get(key)
    if seen is None:
        seen = _sight(scene, pose, visibility, reach)
        with _LOCK:
            remember(scene.sights, key, seen, SIGHT_MEMO)
    return seen


def _sight(scene: Scene, pose: WorldPose, visibility: float, landmarks: float) -> Sight:
    fx, fz = unit(pose.heading)
    rx, rz = right_of(pose.heading)
    dx = scene.samples[..., 0] - pose.x
    dz = scene.samples[..., 1] - pose.z
    fwd = dx * fx + dz * fz
    lat = dx * rx + dz * rz
    limit = np.where(scene.landmarks, landmarks, visibility)[:, None]
    near = (fwd > 0) & (np.abs(lat) <= fwd) & (dx * dx + dz * dz <= limit * limit)
    obj, j = np.nonzero(near)
    clear = in_line_of_sight(scene, np.float64(pose.x), np.float64(pose.z), obj, j)
    mask = np.zeros(len(scene.centres), dtype=bool)
    mask[obj[clear]] = True
    cx = scene.centres[:, 0] - pose.x
    cz = scene.centres[:, 1] - pose.z
    bearing = np.degrees(np.arctan2(cx * rx + cz * rz, cx * fx + cz * fz))
    arrays = (mask, np.clip(bearing, -HALF_FOV, HALF_FOV), np.hypot(cx, cz))
    for a in arrays:
        a.setflags(write=False)  # shared by every caller of the memo
    return Sight(*arrays, scene.layout.objects)


def in_line_of_sight(
    scene: Scene, px: np.ndarray, pz: np.ndarray, obj: np.ndarray, j: np.ndarray
) -> np.ndarray:
    """Whether sample point ``j[m]`` of object ``obj[m]`` is in the line of sight from the
    eye at ``(px, pz)`` (scalars or arrays as long as ``obj``): no wall crosses the segment
    to it, and the line from the eye (1.5 m up) to the object's top above it passes through
    no occluder (:attr:`Scene.occluders`, a box from the floor to its top) other than the
    object and the object it stands on.

    An occluder is crossed between the segment's parameters ``t_in < t_out`` (slab test on
    its footprint, clipped to ``[0, 1]``); the line's height ``EYE + (top - EYE) * t`` is
    linear in ``t``, so it clears the occluder when it is at least the occluder's height
    at both ends of that interval.
    """
    sx, sz = scene.samples[obj, j, 0], scene.samples[obj, j, 1]
    ddx, ddz = sx - px, sz - pz
    clear = ~scene.walls.blocks(px, pz, sx, sz)
    occ = scene.occluders
    if not occ.size or not obj.size:
        return clear
    rects, height = scene.rects[occ], scene.tops[occ]
    ox, oz = np.broadcast_to(px, obj.shape)[:, None], np.broadcast_to(pz, obj.shape)[:, None]
    t_in, t_out = _slab(ox, ddx[:, None], rects[:, 0], rects[:, 2])
    tz_in, tz_out = _slab(oz, ddz[:, None], rects[:, 1], rects[:, 3])
    t_in = np.maximum(np.maximum(t_in, tz_in), 0.0)
    t_out = np.minimum(np.minimum(t_out, tz_out), 1.0)
    rise = (scene.tops[obj] - EYE)[:, None]
    low = np.minimum(EYE + rise * t_in, EYE + rise * t_out)
    own = (occ[None, :] == obj[:, None]) | (occ[None, :] == scene.support[obj][:, None])
    hidden = (t_in < t_out) & (low < height[None, :]) & ~own
    return clear & ~hidden.any(axis=1)


def _slab(
    o: np.ndarray, d: np.ndarray, lo: np.ndarray, hi: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """The parameters ``t`` between which ``o + t d`` lies strictly inside ``(lo, hi)``
    (all ``t`` when ``d == 0`` and ``o`` is inside, none when it is outside)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        a, b = (lo - o) / d, (hi - o) / d
    flat = d == 0
    inside = (o > lo) & (o < hi)
    t_in = np.where(flat, np.where(inside, -np.inf, np.inf), np.minimum(a, b))
    t_out = np.where(flat, np.where(inside, np.inf, -np.inf), np.maximum(a, b))
    return t_in, t_out


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
    """``G_base``: ids visible under the *baseline* condition from some standing point
    (:func:`standing_points`) under any heading, sorted; cached per layout."""
    scene = scene_of(layout)
    params = condition_params("baseline")
    vis, landmarks = params.visibility_distance, params.draw_distance
    limit = np.where(scene.landmarks, landmarks, vis)[:, None] + np.zeros(scene.samples.shape[:2])
    stand = standing_points(scene)
    seen = np.zeros(len(layout.objects), dtype=bool)
    obj_all, j_all = np.indices(scene.samples.shape[:2]).reshape(2, -1)
    for x, z in stand:
        dx = scene.samples[..., 0].ravel() - x
        dz = scene.samples[..., 1].ravel() - z
        near = (dx * dx + dz * dz <= limit.ravel() ** 2) & ~seen[obj_all]
        obj, j = obj_all[near], j_all[near]
        seen[obj[in_line_of_sight(scene, np.float64(x), np.float64(z), obj, j)]] = True
    return tuple(sorted(layout.objects[i].object_id for i in np.flatnonzero(seen)))
