"""Ground truth of an episode in the spawn frame (what the metrics compare maps against)."""

from __future__ import annotations

from pytest_emrd.rooms import SLUG_ROOMS
from pytest_emrd.trajectory import GroundTruth, GroundTruthObject, RoomOutline
from pytest_emrd.world._geometry import to_spawn_frame
from pytest_emrd.world._model import Layout, WorldPose
from pytest_emrd.world._visibility import discoverable_ids


def _point(spawn_pose: WorldPose, x: float, z: float) -> tuple[float, float]:
    sx, sz = to_spawn_frame(spawn_pose, x, z)
    return round(sx, 4) + 0.0, round(sz, 4) + 0.0


def ground_truth(layout: Layout, spawn_pose: WorldPose, spawn_room: str) -> GroundTruth:
    """Every object and room outline of ``layout`` in the frame of ``spawn_pose``.

    ``spawn_room`` may be a canonical name or a slug; ``discoverable_ids`` is ``G_base``
    (:func:`~pytest_emrd.world.discoverable_ids`), the same for every condition.
    """
    objects = tuple(
        GroundTruthObject(
            object_id=o.object_id,
            object_type=o.object_type,
            room=o.room,
            category=o.category,
            x=(p := _point(spawn_pose, o.x, o.z))[0],
            z=p[1],
        )
        for o in layout.objects
    )
    rooms = tuple(
        RoomOutline(
            name=r.name,
            polygon=tuple(
                _point(spawn_pose, x, z)
                for x, z in ((r.x0, r.z0), (r.x1, r.z0), (r.x1, r.z1), (r.x0, r.z1))
            ),
        )
        for r in layout.rooms
    )
    return GroundTruth(
        objects=objects,
        rooms=rooms,
        discoverable_ids=discoverable_ids(layout),
        spawn_room=SLUG_ROOMS.get(spawn_room, spawn_room),
    )
