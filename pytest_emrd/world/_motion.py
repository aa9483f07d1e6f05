"""Semantic motion: where ``Goto`` puts the agent, and where an episode starts.

* ``Goto(object)``: the agent stands 0.7 m (else 0.6 or 0.8 m) in front of a side of the
  object's footprint (for an item on a desk or counter, of the desk or counter), facing it,
  sides facing the agent first, along a side the midpoint first, then 0.4 and 0.8 m either
  way; the spot must lie in the object's room with the agent's radius clear.
* ``Goto(Doorway_N)``: from one of its rooms the agent passes through to 1 m inside the
  other room, facing away from the doorway; a doorway seen from a third room is walked up
  to (1 m before it, facing it), so a single action never skips a room.
* Spawn: the episodes of a room stand on distinct points, :func:`spawn_points`
  (``docs/interpretation/world.md``, "Twenty distinct episodes per spawn room").
"""

from __future__ import annotations

import numpy as np

from pytest_emrd.errors import ConfigError
from pytest_emrd.world._geometry import HEADINGS, Point
from pytest_emrd.world._model import Doorway, Layout, Room, WorldPose
from pytest_emrd.world._rng import StableRng
from pytest_emrd.world._scene import AGENT_RADIUS, Scene

STAND_OFF = (0.7, 0.6, 0.8)
SLIDES = (0.0, -0.4, 0.4, -0.8, 0.8)
THROUGH = 1.0
SPAWN_RADIUS = 1.0
SPAWN_STEP = 0.25
SPAWN_CLEARANCE = 0.6
"""Free space around a spawn point, so the first view is not a table top."""
SPAWN_POSES = 20
"""Spawn points per room at least (the paper's 20 runs per starting room)."""
#: Outward normal of a footprint side -> heading that faces the side from outside.
_SIDES = (((0.0, 1.0), 180.0), ((0.0, -1.0), 0.0), ((1.0, 0.0), 270.0), ((-1.0, 0.0), 90.0))


def is_free(
    scene: Scene, room: Room, x: float | np.ndarray, z: float | np.ndarray, r: float = AGENT_RADIUS
) -> np.ndarray:
    """Whether a disc of radius ``r`` (the agent) fits at ``(x, z)`` inside ``room`` (per point
    when ``x`` and ``z`` are arrays)."""
    inside = (x >= room.x0 + r) & (x <= room.x1 - r) & (z >= room.z0 + r) & (z <= room.z1 - r)
    return inside & ~scene.crowded(x, z, r)


def approach(scene: Scene, index: int, pose: WorldPose) -> WorldPose | None:
    """Where ``Goto`` of object ``index`` puts an agent standing at ``pose`` (None: no spot)."""
    room = scene.layout.room(scene.layout.objects[index].room)
    x0, z0, x1, z1 = scene.rects[scene.support[index]]
    cx, cz = (x0 + x1) / 2, (z0 + z1) / 2
    sides = sorted(_SIDES, key=lambda s: -((pose.x - cx) * s[0][0] + (pose.z - cz) * s[0][1]))
    for (nx, nz), heading in sides:
        mx = x1 if nx > 0 else x0 if nx < 0 else cx
        mz = z1 if nz > 0 else z0 if nz < 0 else cz
        span = ((x1 - x0) / 2 if nx == 0 else (z1 - z0) / 2) + 0.2  # half the side, + 0.2 m
        for off in STAND_OFF:
            for slide in SLIDES:
                if abs(slide) > span:
                    continue
                x = round(mx + nx * off + abs(nz) * slide, 2)
                z = round(mz + nz * off + abs(nx) * slide, 2)
                if is_free(scene, room, x, z):
                    return WorldPose(x, z, heading)
    return None


def doorway_target(
    layout: Layout, doorway: Doorway, pose: WorldPose, current: str
) -> tuple[Room, bool]:
    """The room ``Goto(doorway)`` leads an agent at ``pose`` in room ``current`` to, and
    whether it passes through (from one of the doorway's rooms into the other) rather than
    walks up to the doorway (from a third room, into the doorway's room on its side)."""
    a, b = layout.room(doorway.room_a), layout.room(doorway.room_b)
    if current in (a.name, b.name):
        return (b if current == a.name else a), True
    if doorway.axis == "x":  # rooms lie north and south of the wall at z = doorway.z
        near_a = (pose.z >= doorway.z) == (a.centre[1] >= doorway.z)
    else:
        near_a = (pose.x >= doorway.x) == (a.centre[0] >= doorway.x)
    return (a if near_a else b), False


def through(scene: Scene, doorway: Doorway, pose: WorldPose, current: str) -> WorldPose | None:
    """Where ``Goto(doorway)`` puts an agent at ``pose`` in room ``current`` (None: blocked):
    :data:`THROUGH` metres into the :func:`doorway_target` room, facing away from the doorway
    when passing through, towards it when walking up."""
    target, passing = doorway_target(scene.layout, doorway, pose, current)
    if doorway.axis == "x":  # the wall runs along x: the rooms lie north and south
        north = target.z0 >= doorway.z
        x, z = doorway.x, round(doorway.z + (THROUGH if north else -THROUGH), 2)
        heading = 0.0 if north == passing else 180.0
    else:
        east = target.x0 >= doorway.x
        x, z = round(doorway.x + (THROUGH if east else -THROUGH), 2), doorway.z
        heading = 90.0 if east == passing else 270.0
    return WorldPose(x, z, heading) if is_free(scene, target, x, z) else None


def spawn_pose(scene: Scene, room: Room, seed: int) -> WorldPose:
    """The start pose in ``room`` of the episode with ``seed`` (see the module docstring)."""
    from pytest_emrd.world._episode import episode_index

    points = spawn_points(scene, room)
    rng = StableRng(f"emrd-spawn:{seed}:{room.name}")
    index = episode_index(room.name, seed)
    x, z = points[index % len(points)] if index is not None else rng.choice(points)
    return WorldPose(x, z, rng.choice(HEADINGS))


def spawn_points(scene: Scene, room: Room) -> list[Point]:
    """The spawn points of ``room`` in the order episodes take them (shuffled once per room):
    episode ``i`` stands on point ``i``, its cardinal heading drawn from the episode seed; a
    seed of no episode (a benchmark's) picks a point by the seed."""
    cx, cz = room.centre
    xs = np.arange(room.x0 + AGENT_RADIUS, room.x1 - AGENT_RADIUS + 1e-9, SPAWN_STEP)
    zs = np.arange(room.z0 + AGENT_RADIUS, room.z1 - AGENT_RADIUS + 1e-9, SPAWN_STEP)
    gx, gz = (np.round(g.ravel(), 2) for g in np.meshgrid(xs, zs))
    d2 = (gx - cx) ** 2 + (gz - cz) ** 2
    order = np.lexsort((gz, gx, d2))  # nearest the centre first, ties by position
    for clearance in (SPAWN_CLEARANCE, AGENT_RADIUS):
        ok = is_free(scene, room, gx, gz, clearance)
        free = order[ok[order]]
        if free.size:
            near = free[d2[free] <= SPAWN_RADIUS**2]
            pool = near if near.size >= SPAWN_POSES else free[:SPAWN_POSES]
            points = [(float(gx[k]), float(gz[k])) for k in pool]
            return StableRng(f"emrd-spawn-points:{room.name}").shuffled(points)
    raise ConfigError(f"room={room.name!r} has no free spot for the agent; the layout is full.")
