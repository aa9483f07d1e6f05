"""Fixtures for the world tests: a generated office and a hand-built two-room layout."""

from __future__ import annotations

from collections.abc import Callable

import pytest

from pytest_emrd.world import (
    BuiltinSimulator,
    Doorway,
    Layout,
    Room,
    WorldObject,
    generate_layout,
)

SEED = 7


def _obj(object_id: str, object_type: str, room: str, x: float, z: float, **kw) -> WorldObject:
    sizes = {"Fridge": (0.8, 0.75, 1.9), "Stool": (0.4, 0.4, 0.7), "Doorway": (1.0, 0.1, 2.1)}
    w, d, h = sizes[object_type]
    category = {"Doorway": "landmark", "Fridge": "salient"}.get(object_type, "clutter")
    return WorldObject(object_id, object_type, room, category, x, z, w, d, h, **kw)


@pytest.fixture(scope="session")
def office() -> Layout:
    """The generated office of seed 7."""
    return generate_layout(SEED)


@pytest.fixture(scope="session")
def two_rooms() -> Layout:
    """Office (z 4-8) above Kitchen (z 0-4), 6 m wide, one doorway at x=3.

    ``Fridge_1`` stands straight through the doorway from (3, 6.5); ``Stool_1`` is in the
    Kitchen off to the side, so a wall hides it from anywhere near (3, 6.5).
    """
    return Layout(
        seed=-1,
        width=6.0,
        depth=8.0,
        rooms=(Room("Office", 0.0, 4.0, 6.0, 8.0), Room("Kitchen", 0.0, 0.0, 6.0, 4.0)),
        doorways=(Doorway("Doorway_1", "Office", "Kitchen", 3.0, 4.0, 1.0, "x"),),
        objects=(
            _obj("Doorway_1", "Doorway", "Office", 3.0, 4.0),
            _obj("Fridge_1", "Fridge", "Kitchen", 3.0, 1.0),
            _obj("Stool_1", "Stool", "Kitchen", 0.8, 1.0),
        ),
    )


@pytest.fixture
def new_sim() -> Callable[..., BuiltinSimulator]:
    """Factory of simulators, closed at teardown."""
    made: list[BuiltinSimulator] = []

    def make(**options) -> BuiltinSimulator:
        sim = BuiltinSimulator(**options)
        made.append(sim)
        return sim

    yield make
    for sim in made:
        sim.close()
