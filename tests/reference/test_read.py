"""The scripted agents read exactly what the prompt builders write."""

from __future__ import annotations

import pytest

from pytest_emrd.agent import NEUTRAL_NAMES, build_system_prompt, step_text
from pytest_emrd.errors import ProtocolError
from pytest_emrd.reference._read import (
    previous_reply,
    read_briefing,
    read_percept,
)
from pytest_emrd.rooms import ROOM_NAMES
from pytest_emrd.trajectory import VARIANTS, Pose
from pytest_emrd.world import VisibleObject
from pytest_emrd.world._feedback import with_pose


@pytest.mark.parametrize("variant", [v for v in VARIANTS if v not in ("neutral", "no_inventory")])
def test_briefing_round_trips_the_inventory(inventory, variant) -> None:
    briefing = read_briefing(build_system_prompt(inventory, variant))
    assert briefing.rooms == ROOM_NAMES
    assert briefing.inventory == inventory


def test_briefing_under_neutral_uses_the_aliases(inventory) -> None:
    briefing = read_briefing(build_system_prompt(inventory, "neutral"))
    assert briefing.rooms == ("Room C", "Room A", "Room D", "Room B")  # the default order
    assert briefing.inventory == {alias: inventory[room] for alias, room in NEUTRAL_NAMES.items()}


def test_briefing_without_inventory_has_rooms_only(inventory) -> None:
    briefing = read_briefing(build_system_prompt(inventory, "no_inventory"))
    assert briefing.rooms == ROOM_NAMES and briefing.inventory == {}


def test_percept_round_trips_the_step_text() -> None:
    visible = [
        VisibleObject("Chair_1", "Chair", -12.0, 2.35),
        VisibleObject("Doorway_2", "Doorway", 40.5, 4.0),
    ]
    feedback = with_pose("Goto(Chair) succeeded.", Pose(-1.5, 2.25, 270.0))
    text = step_text(step=7, max_steps=50, feedback=feedback, visible=visible)
    percept = read_percept(text)
    assert (percept.step, percept.max_steps, percept.pose) == (7, 50, Pose(-1.5, 2.25, 270.0))
    assert [(s.object_id, s.object_type, s.bearing, s.distance) for s in percept.visible] == [
        ("Chair_1", "Chair", -12.0, 2.35),
        ("Doorway_2", "Doorway", 40.5, 4.0),
    ]


def test_percept_without_symbolic_list_asks_for_text_modality() -> None:
    feedback = with_pose("Start.", Pose(0, 0, 0))
    text = step_text(step=1, max_steps=50, feedback=feedback, visible=None)
    with pytest.raises(ProtocolError, match="modality 'text' or 'both'"):
        read_percept(text)


@pytest.mark.parametrize(
    ("system", "match"),
    [
        ("You are a helpful assistant.", "no building overview"),
        ("BUILDING OVERVIEW\nrooms: a, b", "does not list the rooms"),
    ],
    ids=["not-emrd", "no-room-list"],
)
def test_unreadable_prompts(system: str, match: str) -> None:
    with pytest.raises(ProtocolError, match=match):
        read_briefing(system)


def test_previous_reply() -> None:
    assert previous_reply([{"role": "user", "content": "x"}]) is None
    messages = [
        {"role": "assistant", "content": '{"plan": {"turns": 1}}'},
        {"role": "user", "content": "y"},
    ]
    assert previous_reply(messages) == {"plan": {"turns": 1}}
    with pytest.raises(ProtocolError, match="not JSON"):
        previous_reply([{"role": "assistant", "content": "I think"}])
