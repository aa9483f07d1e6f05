"""The world of one episode: which office, which spawn room, which seed.

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
from pytest_emrd.trajectory import LAYOUTS, EpisodeSpec
from pytest_emrd.world._layout import generate_layout
from pytest_emrd.world._model import Layout

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
    """The office of an episode with ``seed`` under ``layouts`` (``paper`` or ``generated``)."""
    check_choice("layouts", layouts, LAYOUTS, hint="Use --emrd-layouts=paper or generated.")
    return paper_office() if layouts == "paper" else generate_layout(seed)


def episode_world(spec: EpisodeSpec) -> EpisodeWorld:
    """The world of ``spec``: its office, spawn room and seed."""
    check_choice("spawn", spec.spawn, SLUG_ROOMS)
    return EpisodeWorld(episode_layout(spec.layouts, spec.seed), SLUG_ROOMS[spec.spawn], spec.seed)


INDEXED_EPISODES: Final = 1000
"""Episode indices :func:`episode_index` recognises per spawn room."""


@cache
def _indices(spawn_room: str) -> dict[int, int]:
    slug = ROOM_SLUGS[spawn_room]
    return {EpisodeSpec("", "baseline", slug, i).seed: i for i in range(INDEXED_EPISODES)}


def episode_index(spawn_room: str, seed: int) -> int | None:
    """The index of the episode of ``spawn_room`` (canonical name) whose seed is ``seed``,
    among the first :data:`INDEXED_EPISODES`; None for any other seed."""
    return _indices(spawn_room).get(seed)
