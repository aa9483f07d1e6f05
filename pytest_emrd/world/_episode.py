"""The world of one episode: which office, which spawn room, which seed.

The paper tests a single office ("robustness is limited by testing on a single office"),
20 runs per spawn room. Under the default ``layouts="paper"`` every episode of every model,
condition and prompt variant therefore runs in :func:`paper_office`; episodes differ only
by the spawn pose inside the spawn room (and, under ``texture``, by the colours), both drawn
from the episode seed. ``layouts="generated"`` is the generalisation option: each spawn x
episode gets its own procedurally generated office (:func:`generate_layout` of the episode
seed). The two are separate protocols and are never mixed (case ids, cassette paths,
results and gate cells all carry the layouts).

:func:`episode_world` is the one place that turns an :class:`EpisodeSpec` into a world; the
episode loop, ``emrd render`` and any viewer call it.
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
"""Generator seed of the fixed office (the paper's Figure "Four-room office layout"): the
first seed whose office holds every piece of the full furniture recipe: Office 4 desks with
4 chairs and 3 laptops, 2 shelving units, 2 plants; Conference Room a 3.2 m conference table
with 8 chairs and a television; Kitchen fridge, 2 counter tops, sink, coffee machine,
microwave, stool; Entrance reception desk, 2 armchairs, a plant and the building exit."""


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
    """The index of the episode of ``spawn_room`` (canonical name) whose seed is ``seed``
    (:attr:`EpisodeSpec.seed`, the same for every model, condition and variant), among the
    first :data:`INDEXED_EPISODES`; None for any other seed."""
    return _indices(spawn_room).get(seed)
