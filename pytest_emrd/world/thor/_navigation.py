"""Where THOR should put the agent for a semantic action, and what it sees. Pure maths.

THOR moves on a grid of reachable positions (``GetReachablePositions``) and faces one of
four headings. ``Goto`` is a teleport to a reachable position in the target's room from
which a grid heading looks at the target (:func:`viewpoint`); through a doorway, to the
position in the next room nearest the gap, facing into it (:func:`entry`). THOR's yaw is
the world frame's heading.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from typing import Any

import numpy as np

from pytest_emrd.world._model import Doorway, Room, VisibleObject, WorldPose
from pytest_emrd.world.thor._house import IdTable

HALF_FOV = 45.0
"""Half of THOR's ``fieldOfView=90``, degrees."""
CLEARANCE = 0.5
"""Minimum distance (m) from a target's centre, or from a doorway's wall, to stand at."""
MAX_OFF_AXIS = 30.0
"""How far (deg) off the view axis a Goto target may end up; beyond, a farther spot wins."""
OFF_AXIS_COST = 0.02
"""Metres of extra distance one degree off the view axis is worth when ranking spots."""
ROOM_MARGIN = 0.05
"""Reachable positions closer than this (m) to a room's edge count as in no room."""


def wrap180(angle: float | np.ndarray) -> Any:
    """Angle(s) wrapped to ``[-180, 180)``."""
    return (np.asarray(angle) + 180.0) % 360.0 - 180.0


def heading_to(x0: float, z0: float, x1: float, z1: float) -> float:
    """Heading (deg clockwise from +z, in [0, 360)) from ``(x0, z0)`` towards ``(x1, z1)``."""
    return math.degrees(math.atan2(x1 - x0, z1 - z0)) % 360.0


def bearing(agent: WorldPose, x: float, z: float) -> float:
    """Bearing of ``(x, z)`` relative to the agent's view axis, negative to the left."""
    return float(wrap180(heading_to(agent.x, agent.z, x, z) - agent.heading))


def grid(positions: Iterable[Mapping[str, float]]) -> np.ndarray:
    """``(N, 2)`` array of ``(x, z)`` from THOR's reachable-position dicts."""
    return np.array([(p["x"], p["z"]) for p in positions], dtype=float).reshape(-1, 2)


def _in_room(points: np.ndarray, room: Room) -> np.ndarray:
    x, z = points[:, 0], points[:, 1]
    m = ROOM_MARGIN
    return (x > room.x0 + m) & (x < room.x1 - m) & (z > room.z0 + m) & (z < room.z1 - m)


def _pick(points: np.ndarray, score: np.ndarray, mask: np.ndarray) -> int | None:
    """Index of the lowest score under ``mask``; ties broken by (x, z) so it is stable."""
    idx = np.flatnonzero(mask)
    if idx.size == 0:
        return None
    order = np.lexsort((points[idx, 1], points[idx, 0], np.round(score[idx], 6)))
    return int(idx[order[0]])


def nearest_in_room(
    points: np.ndarray, x: float, z: float, room: Room
) -> tuple[float, float] | None:
    """The reachable position in ``room`` nearest ``(x, z)`` (None if the room has none)."""
    best = _pick(points, np.hypot(points[:, 0] - x, points[:, 1] - z), _in_room(points, room))
    return None if best is None else (float(points[best, 0]), float(points[best, 1]))


def viewpoint(points: np.ndarray, x: float, z: float, room: Room) -> WorldPose | None:
    """Reachable spot in ``room`` nearest ``(x, z)`` with a grid heading that faces it.

    Among spots at least :data:`CLEARANCE` away that leave the target within
    :data:`MAX_OFF_AXIS` of the view axis, ranks by distance plus :data:`OFF_AXIS_COST` per
    degree off axis; else the nearest spot in the room; None if the room has none.
    """
    dx, dz = x - points[:, 0], z - points[:, 1]
    dist = np.hypot(dx, dz)
    heading = np.degrees(np.arctan2(dx, dz)) % 360.0
    snapped = (np.round(heading / 90.0) * 90.0) % 360.0
    off_axis = np.abs(wrap180(heading - snapped))
    inside = _in_room(points, room)
    score = dist + OFF_AXIS_COST * off_axis
    best = _pick(points, score, inside & (dist >= CLEARANCE) & (off_axis <= MAX_OFF_AXIS))
    if best is None:
        best = _pick(points, dist, inside)
    if best is None:
        return None
    px, pz = points[best]
    return WorldPose(float(px), float(pz), float(snapped[best]))


def entry(points: np.ndarray, doorway: Doorway, into: Room) -> WorldPose | None:
    """Reachable spot in ``into`` nearest the doorway, facing into the room, away from the gap."""
    if doorway.axis == "x":  # wall runs along x at z = doorway.z
        north = abs(into.z0 - doorway.z) < abs(into.z1 - doorway.z)
        heading, depth = (
            (0.0, points[:, 1] - doorway.z) if north else (180.0, doorway.z - points[:, 1])
        )
    else:  # wall runs along z at x = doorway.x
        east = abs(into.x0 - doorway.x) < abs(into.x1 - doorway.x)
        heading, depth = (
            (90.0, points[:, 0] - doorway.x) if east else (270.0, doorway.x - points[:, 0])
        )
    dist = np.hypot(points[:, 0] - doorway.x, points[:, 1] - doorway.z)
    inside = _in_room(points, into)
    best = _pick(points, dist, inside & (depth >= CLEARANCE))
    if best is None:
        best = _pick(points, dist, inside)
    if best is None:
        return None
    px, pz = points[best]
    return WorldPose(float(px), float(pz), heading)


def agent_pose(metadata: Mapping[str, Any]) -> WorldPose:
    """The agent's pose from an event's metadata."""
    agent = metadata["agent"]
    return WorldPose(
        float(agent["position"]["x"]),
        float(agent["position"]["z"]),
        float(agent["rotation"]["y"]) % 360.0,
    )


def visible_objects(
    objects: Sequence[Mapping[str, Any]],
    agent: WorldPose,
    *,
    ids: IdTable,
    types: Mapping[str, str],
    landmarks: frozenset[str],
    visibility_distance: float,
) -> tuple[VisibleObject, ...]:
    """EMRD objects THOR reports ``visible``, sorted by id.

    THOR runs with the condition's draw distance, as far as ``landmarks`` (EMRD ids of
    doorways and the exit) count visible; every other object must also lie within
    ``visibility_distance``, measured horizontally to the nearest point of its bounding box.
    ``distance`` is horizontal, to the object's position; ``types`` maps EMRD id -> EMRD
    type; bearings are clipped to the field of view.
    """
    seen: dict[str, VisibleObject] = {}
    for obj in objects:
        if not obj.get("visible"):
            continue
        ours = ids.emrd(str(obj["objectId"]))
        if ours is None:
            continue
        x, z = float(obj["position"]["x"]), float(obj["position"]["z"])
        if ours not in landmarks and _box_distance(obj, agent) > visibility_distance:
            continue
        b = min(HALF_FOV, max(-HALF_FOV, bearing(agent, x, z)))
        distance = round(math.hypot(x - agent.x, z - agent.z), 2)
        seen[ours] = VisibleObject(ours, types[ours], round(b, 1), distance)
    return tuple(seen[k] for k in sorted(seen))


def _box_distance(obj: Mapping[str, Any], agent: WorldPose) -> float:
    """Horizontal distance from the agent to the nearest point of ``obj``'s bounding box."""
    box = obj["axisAlignedBoundingBox"]
    cx, cz = float(box["center"]["x"]), float(box["center"]["z"])
    hx, hz = float(box["size"]["x"]) / 2, float(box["size"]["z"]) / 2
    dx = max(abs(agent.x - cx) - hx, 0.0)
    dz = max(abs(agent.z - cz) - hz, 0.0)
    return math.hypot(dx, dz)
