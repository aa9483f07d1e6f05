"""The vocabulary of free-form labels: what VLMs write -> AI2-THOR engine types."""

from __future__ import annotations

import csv
from collections import Counter
from pathlib import Path

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
from pytest_emrd.metrics._vocab import FUZZY_MIN_LENGTH, REAL_WORDS, TypeResolver
from pytest_emrd.trajectory import GroundTruthObject, MapEntry
from pytest_emrd.world import KINDS

#: The types the built-in office holds.
OFFICE_TYPES = frozenset(kind.object_type for kind in KINDS.values())

#: Labels as VLMs write them, with what each denotes and what it matches in the office
#: (empty: nothing). Kinds: ``plausible`` (office objects in a VLM's words), ``misspelt``,
#: ``wrong`` (objects the office does not hold), ``part`` (a part of an object, or a thing
#: named after one), ``nearword`` (real English words one or two letters from a type name),
#: ``nonfurniture`` (things and words that are no object of the engine).
LABELS = Path(__file__).with_name("vocab_labels.csv")


def _table() -> list[dict[str, str]]:
    with LABELS.open(newline="", encoding="utf-8") as f:
        return list(csv.DictReader(f))


TABLE = _table()


def test_the_office_is_what_the_label_table_assumes() -> None:
    office = str.split(
        "Doorway Door Desk DiningTable ShelvingUnit Television Fridge CounterTop ArmChair "
        "Chair Stool HousePlant Laptop Sink Microwave CoffeeMachine"
    )
    assert frozenset(office) == OFFICE_TYPES


@pytest.mark.parametrize("row", TABLE, ids=[f"{r['kind']}:{r['label']!r}" for r in TABLE])
def test_label_table_row(row: dict[str, str]) -> None:
    assert canonical_type(row["label"]) == (row["denotes"] or None)
    assert canonical_type(row["label"], present=OFFICE_TYPES) == (row["in_office"] or None)


def label_table_shares(rows: list[dict[str, str]]) -> dict[str, tuple[int, int]]:
    """Per kind, and ``all``: (labels matched to an office type, labels)."""
    accepted = Counter(r["kind"] for r in rows if r["in_office"])
    total = Counter(r["kind"] for r in rows)
    shares = {kind: (accepted[kind], n) for kind, n in total.items()}
    shares["all"] = (sum(accepted.values()), len(rows))
    return shares


def test_label_table_shares() -> None:
    """The accepted and refused shares quoted in docs/interpretation/vocabulary.md."""
    assert len(TABLE) >= 150
    shares = label_table_shares(TABLE)
    for kind, (accepted, n) in sorted(shares.items()):
        print(f"{kind:>13}: {n:3d} labels, accepted {accepted:3d} ({accepted / n:6.1%}), "
              f"refused {n - accepted:3d} ({(n - accepted) / n:6.1%})")  # fmt: skip
    assert shares == {
        "plausible": (95, 95),
        "misspelt": (23, 27),
        "wrong": (0, 35),
        "part": (0, 10),
        "nearword": (0, 15),
        "nonfurniture": (0, 20),
        "all": (118, 202),
    }


@pytest.mark.parametrize(
    ("text", "before", "now"),
    [
        ("exit sign", "Door", None),
        ("table lamp", "DiningTable", "DeskLamp"),
        ("lamp on the desk", "Desk", "DeskLamp"),
        ("picture of a plant", "HousePlant", "Painting"),
        ("fridge magnet", "Fridge", None),
        ("chair leg", "Chair", None),
        ("chiar", None, "Chair"),
        ("labtop", None, "Laptop"),
        ("refridgerator", None, "Fridge"),
    ],
    ids=repr,
)
def test_issue_23_regressions_head_noun_and_misspellings(
    text: str, before: str | None, now: str | None
) -> None:
    """The readings issue 23 reported (``before``) and the head-noun reading (``now``)."""
    assert canonical_type(text) == now != before


def test_a_type_the_office_lacks_is_a_hallucination_not_its_neighbour() -> None:
    """Issue 23: ``sofa`` in an office without one became ArmChair."""
    assert candidate_types("sofa") == ("Sofa",)
    assert canonical_type("sofa", present=OFFICE_TYPES) is None
    assert TypeResolver(OFFICE_TYPES).resolve("sofa", "sofa") == -1
    truth = [_obj("ArmChair_1", 0, 0), _obj("Chair_1", 3, 0), _obj("Desk_1", 0, 3)]
    m = match_map([MapEntry("sofa", "sofa", 0.0, 0.0), MapEntry("desk", "desk", 0, 3)], truth)
    assert m.unrecognised == ("sofa",)
    assert "ArmChair_1" not in m.label_of


def test_a_hallucinated_exit_sign_is_not_paired_with_the_door() -> None:
    truth = [_obj("Door_1", 0, 0), _obj("Desk_1", 4, 0)]
    m = match_map([MapEntry("exit sign", "sign", 0.0, 0.0), MapEntry("desk", "", 4, 0)], truth)
    assert m.unrecognised == ("exit sign",)
    assert m.label_of == {"Desk_1": "desk"}


@pytest.mark.parametrize(
    ("text", "expected"),
    [
        ("chir", None),  # 4 letters: below FUZZY_MIN_LENGTH
        ("chiar", "Chair"),  # 1 edit in 5
        ("tabel", "DiningTable"),  # 1 edit in 5
        ("micrwve", None),  # 2 edits in 9: similarity 0.78 < 0.8
        ("refrigertr", "Fridge"),  # 2 edits in 12: 0.83
        ("cable", None),  # a real word, 1 edit from "table"
        ("tablet", None),
        ("handle", None),  # not a misspelt "candle"
        ("perception", None),  # not a misspelt "reception"
        ("cofee machine", None),  # only the head noun is corrected; "machine" names no type
        ("offce chiar", "Chair"),
    ],
    ids=repr,
)
def test_misspellings_are_corrected_conservatively(text: str, expected: str | None) -> None:
    assert canonical_type(text) == expected


def test_no_real_word_is_read_as_a_type() -> None:
    assert REAL_WORDS and all(len(w) >= FUZZY_MIN_LENGTH for w in REAL_WORDS)
    assert [w for w in sorted(REAL_WORDS) if candidate_types(w)] == []


@pytest.mark.parametrize(
    ("text", "present", "expected"),
    [
        ("table", ("DiningTable", "Desk"), "DiningTable"),
        ("table", ("Desk",), "Desk"),
        ("sofa", tuple(sorted(OFFICE_TYPES)), None),
        ("couch", ("ArmChair", "Sofa"), "Sofa"),
        ("seat", ("Sofa",), "Sofa"),
        ("door", ("Door",), "Door"),
        ("window", tuple(sorted(OFFICE_TYPES)), None),
        ("TV stand", tuple(sorted(OFFICE_TYPES)), None),
        ("lamp", ("FloorLamp",), "FloorLamp"),
    ],
    ids=[
        "table-with-table",
        "table-desk-only",
        "sofa-office",
        "couch-is-a-sofa",
        "seat-covers-a-sofa",
        "door-exit-only",
        "window",
        "tv-stand",
        "lamp-floor-only",
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


def test_every_engine_type_reads_as_itself_in_a_layout_holding_it() -> None:
    assert all(canonical_type(t, present={t}) == t for t in ENGINE_TYPES)


#: (singular, plural) phrases of office objects, as a VLM writes them.
PHRASES = [
    ("chair", "chairs"), ("office chair", "office chairs"), ("TV", "TVs"),
    ("fridge", "fridges"), ("potted plant", "potted plants"), ("armchair", "armchairs"),
    ("desk", "desks"), ("bookshelf", "bookshelves"), ("couch", "couches"),
    ("laptop computer", "laptop computers"), ("coffee machine", "coffee machines"),
    ("doorway", "doorways"), ("bar stool", "bar stools"), ("chiar", "chiars"),
    ("table lamp", "table lamps"), ("fridge magnet", "fridge magnets"),
    ("exit sign", "exit signs"),
]  # fmt: skip
numbering = st.sampled_from(["", " 2", "_3", " (2)", " #4", "-5", " b", "(x3)"])
qualifier = st.sampled_from(["", " near the window", " by the door", " on the left"])
prefix = st.sampled_from(["", "the ", "red ", "small wooden ", "Big ", "2 "])
case = st.sampled_from([str, str.upper, str.lower, str.title])


@given(st.sampled_from(PHRASES), st.booleans(), prefix, qualifier, numbering, case)
def test_case_plural_numbering_and_qualifiers_never_change_the_type(
    phrase: tuple[str, str], plural: bool, pre: str, post: str, number: str, cased: object
) -> None:
    singular, many = phrase
    written = cased(f"{pre}{many if plural else singular}{post}{number}")  # type: ignore[operator]
    assert canonical_type(written) == canonical_type(singular)
    assert canonical_type(written, present=OFFICE_TYPES) == canonical_type(
        singular, present=OFFICE_TYPES
    )


@given(st.text(max_size=40))
def test_any_text_gives_an_engine_type_or_none(text: str) -> None:
    found = canonical_type(text)
    assert found is None or found in ENGINE_TYPES
    assert candidate_types(text) == () or found == candidate_types(text)[0]


@given(st.sampled_from([r["label"] for r in TABLE]), st.sets(st.sampled_from(sorted(ENGINE_TYPES))))
def test_a_layout_only_ever_narrows_the_candidates(label: str, present: set[str]) -> None:
    found = canonical_type(label, present=present)
    assert found is None or (found in present and found in candidate_types(label))


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
        MapEntry("doorway to the kitchen", "opening", 6.0, 0.0),
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
    assert m.label_of["Doorway_1"] == "doorway to the kitchen"
    # type "sofa" names no type of this layout; the label "the red armchair" does
    assert m.label_of["ArmChair_1"] == "the red armchair"
    assert aec_score(m, len(truth)) == 1.0
    # the hallucination and the duplicate change nothing: the same map without them scores
    # the same (the min cap of Eq. AEC)
    clean = match_map(written[:-2], truth)
    assert aec_score(clean, len(truth)) == 1.0


EXIT_TYPES = ("Doorway", "Door", "Desk")


@pytest.mark.parametrize(
    ("object_type", "label", "expected"),
    [
        ("door", "d", "Door"),
        ("exit", "e", "Door"),
        ("exit door", "e", "Door"),
        ("front door", "e", "Door"),
        ("", "Door_1", "Door"),
        ("", "door (open)", "Door"),
        ("doorway", "d", "Doorway"),
        ("opening", "d", "Doorway"),
        ("archway", "d", "Doorway"),
        ("", "Doorway_2", "Doorway"),
    ],
    ids=repr,
)
def test_the_exit_is_the_exit(object_type: str, label: str, expected: str) -> None:
    resolver = TypeResolver(EXIT_TYPES)
    assert resolver.names[resolver.resolve(object_type, label)] == expected


def test_door_is_a_doorway_only_where_the_layout_has_no_exit() -> None:
    assert canonical_type("door", present=("Doorway", "Desk")) == "Doorway"


def test_a_perfect_map_whose_exit_is_typed_door_matches_the_exit() -> None:
    truth = [
        _obj("Doorway_1", 0, 0),
        _obj("Doorway_2", 4, 0),
        _obj("Door_1", 8, -4),
        _obj("Desk_1", 2, 3),
    ]
    written = [
        MapEntry("doorway", "doorway", 0, 0),
        MapEntry("opening", "", 4, 0),
        MapEntry("exit", "door", 8, -4),
        MapEntry("Door_1", "", 8, -4.2),
        MapEntry("desk", "desk", 2, 3),
    ]
    m = match_map(written[:3] + written[4:], truth)
    assert m.label_of == {
        "Doorway_1": "doorway",
        "Doorway_2": "opening",
        "Door_1": "exit",
        "Desk_1": "desk",
    }
    assert match_map(written[3:], truth).label_of["Door_1"] == "Door_1"
