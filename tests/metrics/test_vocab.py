"""The vocabulary of free-form labels: what VLMs write -> AI2-THOR engine types."""

from __future__ import annotations

import pytest
from hypothesis import given
from hypothesis import strategies as st

from pytest_emrd.metrics import (
    ENGINE_TYPES,
    SYNONYMS,
    aec_score,
    candidate_types,
    canonical_type,
    match_map,
)
from pytest_emrd.trajectory import GroundTruthObject, MapEntry

#: The types the built-in office holds (see pytest_emrd/world/_catalog.py).
OFFICE_TYPES = frozenset(
    str.split(
        "Doorway Door Desk DiningTable ShelvingUnit Television Fridge CounterTop ArmChair Chair "
        "Stool HousePlant Laptop Sink Microwave CoffeeMachine"
    )
)


@pytest.mark.parametrize(
    ("text", "engine_type"),
    [
        # synonyms
        ("office chair", "Chair"),
        ("TV", "Television"),
        ("flat screen TV", "Television"),
        ("monitor", "Television"),
        ("sofa", "Sofa"),
        ("couch", "Sofa"),
        ("fridge", "Fridge"),
        ("Refrigerator", "Fridge"),
        ("plant", "HousePlant"),
        ("potted plant", "HousePlant"),
        ("door", "Doorway"),
        ("exit door", "Door"),
        ("Emergency exit", "Door"),
        ("coffee maker", "CoffeeMachine"),
        ("microwave oven", "Microwave"),
        ("bookcase", "ShelvingUnit"),
        ("reception desk", "Desk"),
        ("conference table", "DiningTable"),
        # engine names, CamelCase and ids
        ("DiningTable", "DiningTable"),
        ("DiningTable_1", "DiningTable"),
        ("ArmChair_2", "ArmChair"),
        ("TVStand", "TVStand"),
        ("Television", "Television"),
        # plurals, case, numbering
        ("chairs", "Chair"),
        ("Shelves", "ShelvingUnit"),
        ("couches", "Sofa"),
        ("CHAIR", "Chair"),
        ("chair 2", "Chair"),
        ("Chair_3", "Chair"),
        ("Chair3", "Chair"),
        ("chair#2", "Chair"),
        ("chairs (2)", "Chair"),
        ("2 chairs", "Chair"),
        ("stool b", "Stool"),
        ("Desk #4", "Desk"),
        # qualifiers
        ("chair near the window", "Chair"),
        ("small wooden table by the door", "DiningTable"),
        ("the red armchair", "ArmChair"),
        ("laptop on the desk", "Laptop"),
        ("doorway to the kitchen", "Doorway"),
        ("TV on the wall [conference]", "Television"),
        ("back left chair", "Chair"),
        ("L-shaped desk", "Desk"),
        # hallucinations: no engine type
        ("fire extinguisher", None),
        ("ghost", None),
        ("", None),
        ("_3", None),
        ("something shiny", None),
        ("near the window", "Window"),  # no head noun before it: the window is the thing
    ],
    ids=repr,
)
def test_canonical_type_worked_examples(text: str, engine_type: str | None) -> None:
    assert canonical_type(text) == engine_type


@pytest.mark.parametrize(
    ("text", "present", "expected"),
    [
        ("table", ("DiningTable", "Desk"), "DiningTable"),
        ("table", ("Desk",), "Desk"),
        ("sofa", tuple(sorted(OFFICE_TYPES)), "ArmChair"),
        ("door", ("Door",), "Door"),
        ("window", tuple(sorted(OFFICE_TYPES)), None),
        ("TV stand", tuple(sorted(OFFICE_TYPES)), None),
    ],
    ids=[
        "table-with-table",
        "table-desk-only",
        "sofa-office",
        "door-exit-only",
        "window",
        "tv-stand",
    ],
)
def test_present_types_pick_the_candidate_the_layout_holds(
    text: str, present: tuple[str, ...], expected: str | None
) -> None:
    assert canonical_type(text, present=present) == expected


def test_every_synonym_denotes_engine_types_only() -> None:
    assert all(set(types) <= ENGINE_TYPES for types in SYNONYMS.values())
    assert all(types for types in SYNONYMS.values())


def test_every_office_type_is_an_engine_type_and_reads_as_itself() -> None:
    assert OFFICE_TYPES <= ENGINE_TYPES
    assert all(canonical_type(t) == t for t in OFFICE_TYPES - {"Door"})


words = st.sampled_from(["chair", "office chair", "TV", "fridge", "plant", "armchair", "desk"])
qualifier = st.sampled_from(["", " near the window", " by the door", " (2)", " #3", "_4", "s"])
prefix = st.sampled_from(["", "the ", "red ", "small wooden ", "Big "])


@given(prefix, words, qualifier)
def test_decoration_never_changes_the_type(pre: str, word: str, post: str) -> None:
    assert canonical_type(f"{pre}{word}{post}") == canonical_type(word)
    assert canonical_type(f"{pre}{word}{post}".upper()) == canonical_type(word)


@given(st.text(max_size=40))
def test_any_text_gives_an_engine_type_or_none(text: str) -> None:
    found = canonical_type(text)
    assert found is None or found in ENGINE_TYPES
    assert candidate_types(text) == () or found == candidate_types(text)[0]


def _obj(oid: str, x: float, z: float) -> GroundTruthObject:
    return GroundTruthObject(oid, oid.rsplit("_", 1)[0], "Office", "salient", x, z)


def test_a_real_looking_vlm_map_is_read_like_the_engine_ids() -> None:
    truth = [
        _obj("Chair_1", 0, 0), _obj("Chair_2", 2, 0), _obj("Desk_1", 1, 1),
        _obj("Television_1", 5, 3), _obj("Fridge_1", -4, -3), _obj("HousePlant_1", 3, -2),
        _obj("Doorway_1", 6, 0), _obj("Door_1", 8, -4), _obj("ArmChair_1", 7, -3),
    ]  # fmt: skip
    written = [
        MapEntry("office chair 1", "office chair", 0.1, 0.0),
        MapEntry("chair near the window", "", 2.0, 0.1),
        MapEntry("wooden desk", "desk", 1.0, 1.0),
        MapEntry("TV", "TV", 5.0, 3.0),
        MapEntry("fridge", "refrigerator", -4.0, -3.0),
        MapEntry("plant (2)", "Potted plant", 3.0, -2.0),
        MapEntry("door to the kitchen", "door", 6.0, 0.0),
        MapEntry("exit", "Exit door", 8.0, -4.0),
        MapEntry("the red armchair", "sofa", 7.0, -3.0),
        MapEntry("fire extinguisher", "extinguisher", 6.5, -4.0),
        MapEntry("chairs (2)", "chairs", 0.5, 0.4),
    ]
    m = match_map(written, truth)
    assert m.unrecognised == ("fire extinguisher",)
    assert m.unmatched == ("chairs (2)",)  # a third chair: beyond the two the office has
    assert len(m.pairs) == len(truth)
    assert m.label_of["Chair_2"] == "chair near the window"
    assert m.label_of["Door_1"] == "exit"
    assert m.label_of["Doorway_1"] == "door to the kitchen"
    assert aec_score(m, len(truth)) == 1.0
    # the hallucination and the duplicate change nothing: the same map without them scores
    # the same (the min cap of Eq. AEC)
    clean = match_map(written[:-2], truth)
    assert aec_score(clean, len(truth)) == 1.0
