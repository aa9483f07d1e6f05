"""Every prompt variant's claims are true of the world it runs in.

Over the paper's office and generated layouts, every variant and modality: the room names
map one to one onto the four rooms, every furniture profile reads back to the room's real
contents, the Goto type list is exactly the types in the office, and B3's "2 doorways
connecting to adjacent rooms" holds for every room.
"""

from __future__ import annotations

import re

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pytest_emrd.agent import ROOM_SUFFIXES, build_system_prompt, room_aliases
from pytest_emrd.agent._prompt import GOTO_TYPES_LEAD, OVERVIEW_HEADING, read_profile
from pytest_emrd.metrics import aec_score, match_map
from pytest_emrd.rooms import ROOM_NAMES
from pytest_emrd.trajectory import MODALITIES, VARIANTS, MapEntry
from pytest_emrd.world import Layout, WorldPose, generate_layout, ground_truth, paper_office
from pytest_emrd.world._layout import PAIRS

_ROOMS = re.compile(r"^The building has four rooms: (?P<names>.+)\.$", re.MULTILINE)
_LINE = re.compile(r"^- (?P<label>[^:]+): (?P<items>[^.]*)\.(?: (?P<suffix>.*))?$", re.MULTILINE)


def check_claims(layout: Layout, variant: str, modality: str) -> None:
    text = build_system_prompt(layout.inventory(), variant, modality=modality)
    aliases = room_aliases(variant)
    labels = [n.strip() for n in _ROOMS.search(text)["names"].split(",")]  # type: ignore[index]
    assert sorted(aliases[label] for label in labels) == sorted(ROOM_NAMES)
    overview = text.split(OVERVIEW_HEADING, 1)[1].split("\n\n", 1)[0]
    lines = list(_LINE.finditer(overview))
    if variant == "no_inventory":
        assert lines == []
    else:
        assert [m["label"] for m in lines] == labels
        for m in lines:
            assert read_profile(m["items"]) == layout.inventory()[aliases[m["label"]]]
            assert m["suffix"] == ROOM_SUFFIXES.get(variant)
    goto = next(line for line in text.splitlines() if line.startswith(GOTO_TYPES_LEAD))
    listed = set(goto.removeprefix(GOTO_TYPES_LEAD).strip(" .").split(", "))
    assert listed == {o.object_type for o in layout.objects}
    if variant == "B3":  # "2 doorways connecting to adjacent rooms", in every room
        for room in ROOM_NAMES:
            doors = [d for d in layout.doorways if room in (d.room_a, d.room_b)]
            assert len(doors) == 2
            assert all((d.room_a, d.room_b) in PAIRS for d in doors)


@pytest.mark.parametrize("modality", MODALITIES)
@pytest.mark.parametrize("variant", VARIANTS)
def test_claims_hold_in_the_paper_office(variant: str, modality: str) -> None:
    check_claims(paper_office(), variant, modality)


@settings(max_examples=40, deadline=None)
@given(
    seed=st.integers(0, 2**32 - 1),
    variant=st.sampled_from(VARIANTS),
    modality=st.sampled_from(MODALITIES),
)
def test_claims_hold_in_generated_layouts(seed: int, variant: str, modality: str) -> None:
    check_claims(generate_layout(seed), variant, modality)


#: What the MAP goal asks for, phrase -> the engine types it names beyond the profiles.
_ASKED_BEYOND_PROFILES = {"every doorway": "Doorway", "the building exit": "Door"}


def _asked_types(text: str) -> set[str]:
    """The engine types the default prompt asks the model to map: every type of the furniture
    profiles (MAP: "every object you discover: each piece of furniture, each item on a desk
    or counter") plus the landmarks the MAP line names."""
    goal = next(line for line in text.splitlines() if line.startswith("2. MAP:"))
    assert "every object you discover" in goal, goal
    profiles = [m["items"] for m in _LINE.finditer(text.split(OVERVIEW_HEADING, 1)[1])]
    asked = {t for items in profiles for t in read_profile(items)}
    return asked | {t for phrase, t in _ASKED_BEYOND_PROFILES.items() if phrase in goal}


@pytest.mark.parametrize("modality", MODALITIES)
def test_a_model_mapping_exactly_what_it_is_asked_for_reaches_aec_1(modality: str) -> None:
    """The prompt asks for every object ``E`` holds (doorways and the exit included), so the
    AEC ceiling of a model that maps exactly what it is asked for is 1.0 (under ``p2``'s
    "every salient piece of furniture" it was 37/41 = 0.902 on the paper office)."""
    office = paper_office()
    spawn = WorldPose(3.0, 7.0, 90.0)
    truth = ground_truth(office, spawn, "office")
    asked = _asked_types(build_system_prompt(office.inventory(), "default", modality=modality))
    assert {o.object_type for o in truth.objects} <= asked
    entries = [
        MapEntry(o.object_id.lower(), o.object_type, o.x, o.z, o.room)
        for o in truth.objects
        if o.object_type in asked
    ]
    assert aec_score(match_map(entries, truth.objects), len(truth.objects)) == 1.0
    furniture_only = [e for e in entries if e.object_type not in ("Doorway",)]
    assert aec_score(match_map(furniture_only, truth.objects), len(truth.objects)) == 37 / 41
