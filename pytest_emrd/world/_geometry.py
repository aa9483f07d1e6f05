"""2-D geometry shared by the layout, visibility, motion and the renderer.

Walls are zero-thickness axis-aligned segments on the room boundaries, with gaps at the
doorways; visibility and the renderer use the same :class:`Walls`, so they cannot disagree
about occlusion. :func:`unit` is exact for multiples of 90 degrees, the only headings the
built-in world produces, so rendered pixels are bit-stable.
"""

from __future__ import annotations

import math
from collections import defaultdict
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from pytest_emrd.world._model import Layout, WorldObject, WorldPose

Rect = tuple[float, float, float, float]
"""Axis-aligned rectangle ``(x0, z0, x1, z1)`` with ``x0 <= x1`` and ``z0 <= z1``."""
Point = tuple[float, float]
"""A point ``(x, z)`` of the floor, metres."""
Span = tuple[float, float]
"""An interval ``(lo, hi)`` along one axis."""

HEADINGS = (0.0, 90.0, 180.0, 270.0)
"""The cardinal headings, the only ones the built-in world's poses and turns produce."""
_CARDINAL = {0: (0.0, 1.0), 90: (1.0, 0.0), 180: (0.0, -1.0), 270: (-1.0, 0.0)}


def unit(heading: float) -> tuple[float, float]:
    """The unit vector ``(x, z)`` a heading points along (exact for multiples of 90)."""
    h = heading % 360
    if h in _CARDINAL:
        return _CARDINAL[int(h)]
    rad = math.radians(h)
    return math.sin(rad), math.cos(rad)


def right_of(heading: float) -> tuple[float, float]:
    """The unit vector pointing to the right of ``heading``."""
    return unit(heading + 90)


def footprint(obj: WorldObject) -> Rect:
    """The object's axis-aligned floor footprint.

    :param obj: The object, rotated by its ``rotation``.
    :returns: Its footprint rectangle in world coordinates.
    """
    return rect_at(obj.x, obj.z, obj.width, obj.depth, obj.rotation)


def rect_at(x: float, z: float, width: float, depth: float, rotation: float) -> Rect:
    """Footprint of a ``width x depth`` box centred at ``(x, z)`` turned by ``rotation``."""
    if round(rotation) % 180 == 90:
        width, depth = depth, width
    return (x - width / 2, z - depth / 2, x + width / 2, z + depth / 2)


def rects_at(
    x: np.ndarray, z: np.ndarray, width: float, depth: float, rotation: np.ndarray
) -> np.ndarray:
    """``(K, 4)`` footprints of boxes centred at ``(x[k], z[k])`` turned by ``rotation[k]``."""
    turned = np.round(rotation) % 180 == 90
    hw = np.where(turned, depth, width) / 2
    hd = np.where(turned, width, depth) / 2
    return np.stack([x - hw, z - hd, x + hw, z + hd], axis=1)


def local_to_world(x: float, z: float, rotation: float, u: float, v: float) -> Point:
    """World point at ``u`` metres right and ``v`` metres forward of a frame at ``(x, z)``.

    :param x: The frame's origin, world x.
    :param z: The frame's origin, world z.
    :param rotation: The frame's heading in degrees.
    :param u: Metres to the frame's right.
    :param v: Metres forward.
    :returns: The world ``(x, z)``.
    """
    fx, fz = unit(rotation)
    rx, rz = right_of(rotation)
    return x + u * rx + v * fx, z + u * rz + v * fz


def to_spawn_frame(spawn_pose: WorldPose, x: float, z: float) -> Point:
    """World ``(x, z)`` -> spawn frame: origin at the spawn position, ``+z`` along the spawn
    heading, ``+x`` to the agent's right.

    :param spawn_pose: The spawn pose defining the frame.
    :param x: World x.
    :param z: World z.
    :returns: ``(x, z)`` in the spawn frame, metres.
    """
    dx, dz = x - spawn_pose.x, z - spawn_pose.z
    fx, fz = unit(spawn_pose.heading)
    rx, rz = right_of(spawn_pose.heading)
    return dx * rx + dz * rz, dx * fx + dz * fz


def spawn_frame_point(spawn_pose: WorldPose, x: float, z: float) -> Point:
    """:func:`to_spawn_frame` as positions are reported: to 0.1 mm, never ``-0.0``."""
    sx, sz = to_spawn_frame(spawn_pose, x, z)
    return round(sx, 4) + 0.0, round(sz, 4) + 0.0


def heading_in_spawn_frame(spawn_pose: WorldPose, heading: float) -> float:
    """World heading -> degrees clockwise from the spawn heading, in ``[0, 360)``.

    :param spawn_pose: The spawn pose the heading is measured from.
    :param heading: A world heading in degrees.
    :returns: Degrees in ``[0, 360)``.
    """
    relative = (heading - spawn_pose.heading) % 360
    return 0.0 if relative >= 360 else relative  # -1e-20 % 360 rounds up to 360.0


def rects_overlap(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``(K, M)`` bool: does rect ``a[k]`` overlap rect ``b[m]`` with positive area."""
    overlap_x = (a[:, None, 0] < b[None, :, 2]) & (a[:, None, 2] > b[None, :, 0])
    overlap_z = (a[:, None, 1] < b[None, :, 3]) & (a[:, None, 3] > b[None, :, 1])
    return overlap_x & overlap_z


@dataclass(frozen=True, eq=False)
class Walls:
    """Wall segments: ``along_x`` rows ``(z, x0, x1)``, ``along_z`` rows ``(x, z0, z1)``."""

    along_x: np.ndarray
    along_z: np.ndarray

    def first_hit(
        self, ox: np.ndarray, oz: np.ndarray, dx: np.ndarray, dz: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """Ray parameter of the nearest wall hit along ``o + t d`` (``inf`` if none), and
        whether that wall runs along x (True on a tie and when nothing is hit); the arguments
        broadcast to one shape."""
        ox, oz, dx, dz = np.broadcast_arrays(*(np.asarray(a, np.float64) for a in (ox, oz, dx, dz)))
        t_x = _nearest(oz, ox, dz, dx, self.along_x)
        t_z = _nearest(ox, oz, dx, dz, self.along_z)
        return np.minimum(t_x, t_z), t_x <= t_z


def _nearest(
    across: np.ndarray,
    along: np.ndarray,
    d_across: np.ndarray,
    d_along: np.ndarray,
    segs: np.ndarray,
) -> np.ndarray:
    """Nearest ``t > 1e-9`` at which ``across + t * d_across == c`` with ``lo <= along + t *
    d_along <= hi`` for a segment ``(c, lo, hi)``; ``inf`` where none is met."""
    if segs.size == 0:
        return np.full(across.shape, np.inf)
    lead = (-1,) + (1,) * across.ndim
    c, lo, hi = (segs[:, i].reshape(lead) for i in range(3))
    with np.errstate(divide="ignore", invalid="ignore"):
        t = (c - across) / d_across
        hit = along + t * d_along
    ok = (t > 1e-9) & (hit >= lo) & (hit <= hi) & np.isfinite(t)
    return np.where(ok, t, np.inf).min(axis=0)


@lru_cache(maxsize=64)
def walls_of(layout: Layout) -> Walls:
    """The layout's walls: every room edge, merged, with the doorway gaps cut out."""
    lines: defaultdict[tuple[str, float], list[Span]] = defaultdict(list)
    for r in layout.rooms:
        for z in (r.z0, r.z1):
            lines["x", z].append((r.x0, r.x1))
        for x in (r.x0, r.x1):
            lines["z", x].append((r.z0, r.z1))
    gaps: defaultdict[tuple[str, float], list[Span]] = defaultdict(list)
    for d in layout.doorways:
        at, mid = (d.z, d.x) if d.axis == "x" else (d.x, d.z)
        gaps[d.axis, at].append((mid - d.width / 2, mid + d.width / 2))
    rows: dict[str, list[tuple[float, float, float]]] = {"x": [], "z": []}
    for (axis, at), spans in sorted(lines.items()):
        rows[axis] += [(at, lo, hi) for lo, hi in _subtract(_merge(spans), gaps[axis, at])]
    return Walls(
        along_x=np.array(rows["x"], dtype=float).reshape(-1, 3),
        along_z=np.array(rows["z"], dtype=float).reshape(-1, 3),
    )


def _merge(spans: list[Span]) -> list[Span]:
    out: list[Span] = []
    for lo, hi in sorted(spans):
        if out and lo <= out[-1][1]:
            out[-1] = (out[-1][0], max(out[-1][1], hi))
        else:
            out.append((lo, hi))
    return out


def _subtract(spans: list[Span], holes: list[Span]) -> list[Span]:
    for h_lo, h_hi in holes:  # keep what lies left and right of the hole
        parts = [((lo, min(hi, h_lo)), (max(lo, h_hi), hi)) for lo, hi in spans]
        spans = [(lo, hi) for pair in parts for lo, hi in pair if lo < hi]
    return spans
