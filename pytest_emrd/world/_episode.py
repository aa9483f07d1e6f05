"""The world of one episode: which office, which spawn room, which seed; its ground truth.

Under ``layouts="paper"`` every episode runs in :func:`paper_office` (the paper tests a
single office) and episodes differ only by the spawn pose (and, under ``texture``, the
colours), drawn from the episode seed; ``layouts="generated"`` gives each episode its own
office, :func:`generate_layout` of its seed. :func:`episode_world` is the one place that
turns an :class:`EpisodeSpec` into a world.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cache
from typing import Final

from pytest_emrd.errors import check_choice
from pytest_emrd.rooms import ROOM_SLUGS, SLUG_ROOMS
from pytest_emrd.trajectory import LAYOUTS, EpisodeSpec, GroundTruth, GroundTruthObject, RoomOutline
from pytest_emrd.world._geometry import Point, spawn_frame_point
from pytest_emrd.world._layout import generate_layout
from pytest_emrd.world._model import Layout, Room, WorldPose
from pytest_emrd.world._visibility import discoverable_ids

PAPER_OFFICE_SEED: Final = 37
"""Generator seed of the fixed office: the first seed whose office holds every piece of the
full furniture recipe (4 desks, 3 laptops, 2 shelving units, a 3.2 m conference table)."""


@cache
def paper_office() -> Layout:
    """The fixed four-room office of the paper protocol (the same object on every call)."""
    return generate_layout(PAPER_OFFICE_SEED)


@dataclass(frozen=True)
class EpisodeWorld:
    """What a simulator needs to start the episode of a spec."""

    layout: Layout
    spawn_room: str
    """Canonical name of the spawn room."""
    seed: int
    """Episode seed: spawn pose inside the spawn room and the ``texture`` palette."""


def episode_layout(layouts: str, seed: int) -> Layout:
    """The office of an episode with ``seed`` under ``layouts`` (``paper`` or ``generated``).

    :param layouts: ``paper`` for the paper's fixed office, ``generated`` for one per seed.
    :param seed: The episode's seed (unused under ``paper``).
    :returns: The episode's :class:`Layout`.
    """
    check_choice("layouts", layouts, LAYOUTS, hint="Use --emrd-layouts=paper or generated.")
    return paper_office() if layouts == "paper" else generate_layout(seed)


def episode_world(spec: EpisodeSpec) -> EpisodeWorld:
    """The world of ``spec``: its office, spawn room and seed.

    :param spec: The episode.
    :returns: Its :class:`EpisodeWorld`.
    """
    check_choice("spawn", spec.spawn, SLUG_ROOMS)
    return EpisodeWorld(episode_layout(spec.layouts, spec.seed), SLUG_ROOMS[spec.spawn], spec.seed)


INDEXED_EPISODES: Final = 1000
"""Episode indices :func:`episode_index` recognises per spawn room."""


@cache
def _indices(spawn_room: str) -> dict[int, int]:
    slug = ROOM_SLUGS[spawn_room]
    return {EpisodeSpec("", "baseline", slug, i).seed: i for i in range(INDEXED_EPISODES)}


def episode_index(spawn_room: str, seed: int) -> int | None:
    """The index (below :data:`INDEXED_EPISODES`) of the ``spawn_room`` episode of ``seed``."""
    return _indices(spawn_room).get(seed)


def _corners(r: Room) -> tuple[Point, ...]:
    return ((r.x0, r.z0), (r.x1, r.z0), (r.x1, r.z1), (r.x0, r.z1))


def ground_truth(layout: Layout, spawn_pose: WorldPose, spawn_room: str) -> GroundTruth:
    """Every object and room outline of ``layout`` in the frame of ``spawn_pose``.

    ``spawn_room`` may be a canonical name or a slug; ``discoverable_ids`` is ``G_base``
    (:func:`~pytest_emrd.world.discoverable_ids`), the same for every condition.

    :param layout: The office.
    :param spawn_pose: The pose whose frame the positions are given in.
    :param spawn_room: The room the agent starts in.
    :returns: The :class:`GroundTruth` the metrics compare maps against.
    """
    objects = tuple(
        GroundTruthObject(
            o.object_id, o.object_type, o.room, o.category, *spawn_frame_point(spawn_pose, o.x, o.z)
        )
        for o in layout.objects
    )
    rooms = tuple(
        RoomOutline(r.name, tuple(spawn_frame_point(spawn_pose, x, z) for x, z in _corners(r)))
        for r in layout.rooms
    )
    return GroundTruth(
        objects=objects,
        rooms=rooms,
        discoverable_ids=discoverable_ids(layout),
        spawn_room=SLUG_ROOMS.get(spawn_room, spawn_room),
    )
