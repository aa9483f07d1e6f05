"""System prompt per variant (snapshots), the exact differences between variants, aliases."""

from __future__ import annotations

import os
import re
from pathlib import Path

import pytest
from hypothesis import given
from hypothesis import strategies as st

from pytest_emrd.agent import (
    NEUTRAL_NAMES,
    ROOM_SUFFIXES,
    build_system_prompt,
    resolve_room,
    room_aliases,
    step_text,
)
from pytest_emrd.agent._prompt import FURNITURE, furniture_profile, read_profile
from pytest_emrd.errors import ConfigError
from pytest_emrd.rooms import ROOM_NAMES
from pytest_emrd.trajectory import VARIANTS, Pose
from pytest_emrd.world import VisibleObject
from pytest_emrd.world._feedback import with_pose

SNAPSHOTS = Path(__file__).parent / "snapshots"


@pytest.mark.parametrize("variant", VARIANTS)
def test_system_prompt_matches_snapshot(inventory, variant) -> None:
    """After an intended change: EMRD_UPDATE_SNAPSHOTS=1, and bump PROMPT_VERSION."""
    text = build_system_prompt(inventory, variant)
    path = SNAPSHOTS / f"system_{variant}.txt"
    if os.environ.get("EMRD_UPDATE_SNAPSHOTS") == "1":
        path.write_text(text)
    assert text == path.read_text()


def _lines(text: str) -> list[str]:
    return text.splitlines()


@pytest.mark.parametrize("variant", sorted(ROOM_SUFFIXES))
def test_body_interventions_append_the_same_suffix_to_every_room(inventory, variant) -> None:
    base = _lines(build_system_prompt(inventory, "default"))
    changed = _lines(build_system_prompt(inventory, variant))
    diffs = [(a, b) for a, b in zip(base, changed, strict=True) if a != b]
    assert [a.split(":")[0] for a, _ in diffs] == [f"- {room}" for room in ROOM_NAMES]
    for before, after in diffs:
        assert after == f"{before} {ROOM_SUFFIXES[variant]}"


def test_neutral_follows_appendix_e_names_in_the_default_order(inventory) -> None:
    """Appendix E: (Conference Room, Entrance, Office, Kitchen) become Room A-D; "all other
    prompt components remain identical", so the lines keep the default order and the
    neutral prompt is the default one with the names replaced."""
    assert list(NEUTRAL_NAMES.items()) == [
        ("Room A", "Conference Room"),
        ("Room B", "Entrance"),
        ("Room C", "Office"),
        ("Room D", "Kitchen"),
    ]
    base = build_system_prompt(inventory, "default")
    neutral = build_system_prompt(inventory, "neutral")
    assert not [name for name in ROOM_NAMES if re.search(rf"\b{name}\b", neutral)]
    assert "The building has four rooms: Room C, Room A, Room D, Room B." in _lines(neutral)
    renamed = base.replace(
        "The building has four rooms: Office, Conference Room, Kitchen, Entrance.",
        "The building has four rooms: Room C, Room A, Room D, Room B.",
    )
    for alias, room in NEUTRAL_NAMES.items():
        renamed = renamed.replace(f"- {room}:", f"- {alias}:")
    assert _lines(renamed) == _lines(neutral)
    assert (
        "- Room A: a large conference table (DiningTable) + 8 chairs (Chair), "
        "a wall-mounted television (Television)." in _lines(neutral)
    )


def test_no_inventory_keeps_type_names_but_drops_counts_and_mapping(inventory) -> None:
    text = build_system_prompt(inventory, "no_inventory")
    assert "Office, Conference Room, Kitchen, Entrance" in text
    types = {t for counts in inventory.values() for t in counts} | {"Doorway"}
    goto_line = next(line for line in _lines(text) if line.startswith("Object types"))
    assert set(goto_line.split(": ", 1)[1].rstrip(".").split(", ")) == types
    assert "Furniture profile" not in text and "(Chair)" not in text
    assert not re.search(r"\d+ (chairs|desks)", text)
    assert not any(line.startswith(f"- {room}:") for line in _lines(text) for room in ROOM_NAMES)


@pytest.mark.parametrize(
    ("modality", "goto"),
    [("vision", "Goto(type)"), ("text", "Goto(target)"), ("both", "Goto(target)")],
)
def test_prompt_states_goals_budget_actions_and_reply_format(inventory, modality, goto) -> None:
    text = build_system_prompt(inventory, "default", modality=modality, max_steps=30)
    for needle in (
        "autonomous emergency responder",
        "evacuated",
        "safest evacuation gathering point",
        "budget of 30 actions",
        "DEDUPLICATION CHECK",
        "safest room",
        "a large conference table (DiningTable) + 8 chairs (Chair)",
        goto,
        "Turn(Left)",
        "Turn(Around)",
        "Term(room)",
        "Term always ends the run",
        '"cognitive_map"',
        '"dedup_check"',
        '"reasoning"',
    ):
        assert needle in text
    assert ("Goto(Desk_2)" in text) is (modality != "vision")
    assert ("camera frame" in text) is (modality != "text")


def test_room_aliases() -> None:
    assert room_aliases("neutral")["Room A"] == "Conference Room"
    assert set(room_aliases("neutral").values()) == set(ROOM_NAMES)
    assert room_aliases("B3") == {name: name for name in ROOM_NAMES}


@pytest.mark.parametrize(
    ("text", "variant", "expected"),
    [
        ("Room A", "neutral", "Conference Room"),
        ("  'room d' ", "neutral", "Kitchen"),
        ("conference   room", "default", "Conference Room"),
        ("Kitchen", "neutral", "Kitchen"),
        ("entrance", "B1", "Entrance"),
        ("Room A", "default", None),
        ("Lobby", "default", None),
    ],
    ids=[
        "alias",
        "alias-quoted-case",
        "spaces",
        "canonical-under-neutral",
        "slug",
        "alias-off",
        "unknown",
    ],
)
def test_resolve_room(text, variant, expected) -> None:
    assert resolve_room(text, variant) == expected


def test_unknown_variant_is_a_config_error(inventory) -> None:
    with pytest.raises(ConfigError, match=r"variant='B5' is not one of"):
        build_system_prompt(inventory, "B5")


def test_step_text_carries_counter_feedback_with_one_pose_line_and_symbolic_list() -> None:
    visible = [VisibleObject("Chair_1", "Chair", -12.04, 2.345)]
    feedback = with_pose("Turn(Right) succeeded.", Pose(1.2, -0.4, 90.0))
    text = step_text(step=3, max_steps=50, feedback=feedback, visible=visible)
    assert text.splitlines() == [
        "Step 3 of 50.",
        "Engine feedback: Turn(Right) succeeded. Pose: x=1.20 z=-0.40 heading=90.",
        "Visible objects (id | type | bearing deg, negative = left | distance m):",
        "- Chair_1 | Chair | -12.0 | 2.35",
    ]
    assert text.count("Pose:") == 1
    vision_only = step_text(step=3, max_steps=50, feedback=feedback, visible=None)
    assert "Visible" not in vision_only


@given(
    counts=st.dictionaries(
        st.sampled_from([*FURNITURE, "Shelf", "ExitDoor"]), st.integers(1, 12), max_size=8
    ),
    room=st.sampled_from(ROOM_NAMES),
)
def test_furniture_profile_reads_back_to_the_counts(counts: dict[str, int], room: str) -> None:
    text = furniture_profile(room, counts)
    assert read_profile(text) == counts
    assert (text == "nothing listed") is (not counts)


def test_furniture_profile_worked_example() -> None:
    assert furniture_profile("Conference Room", {"Chair": 8, "DiningTable": 1}) == (
        "a large conference table (DiningTable) + 8 chairs (Chair)"
    )
    assert furniture_profile("Entrance", {"Desk": 1, "ArmChair": 2}) == (
        "a reception desk (Desk), 2 armchairs (ArmChair)"
    )
