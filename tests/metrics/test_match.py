"""match_map: types, the robust frame, the gate, per-type assignment, the AEC cap."""

from __future__ import annotations

import math
from collections.abc import Callable

import pytest
from hypothesis import given
from hypothesis import strategies as st

from pytest_emrd.metrics import (
    GATE_M,
    aec_score,
    match_map,
    positional_accuracy_score,
    step_matchings,
)
from pytest_emrd.rooms import CONFERENCE, KITCHEN
from pytest_emrd.trajectory import GroundTruthObject, MapEntry

MakeObj = Callable[..., GroundTruthObject]

coord = st.floats(-20, 20, allow_nan=False, allow_infinity=False)


def test_synonyms_and_label_fallback_resolve_types(make_obj: MakeObj) -> None:
    truth = [
        make_obj("DiningTable_1"),
        make_obj("Television_1", x=1),
        make_obj("HousePlant_1", x=2),
        make_obj("Fridge_1", x=3),
        make_obj("Doorway_1", x=4),
        make_obj("Door_1", x=5),
        make_obj("Chair_1", x=6),
    ]
    entries = [
        MapEntry("t", "table", 0, 0),
        MapEntry("screen", "TV", 1, 0),
        MapEntry("p", "plant", 2, 0),
        MapEntry("f", "refrigerator", 3, 0),
        MapEntry("gap", "door frame", 4, 0),
        MapEntry("way out", "exit", 5, 0),
        MapEntry("Chair_7", "", 6, 0),
        MapEntry("couch", "Sofa", 7, 0),
    ]
    m = match_map(entries, truth)
    assert m.label_of == {
        "DiningTable_1": "t",
        "Television_1": "screen",
        "HousePlant_1": "p",
        "Fridge_1": "f",
        "Doorway_1": "gap",
        "Door_1": "way out",
        "Chair_1": "Chair_7",
    }
    assert m.unrecognised == ("couch",)


def test_table_means_the_table_type_the_layout_has(make_obj: MakeObj) -> None:
    assert match_map([MapEntry("t", "table", 0, 0)], [make_obj("Desk_1")]).label_of == {
        "Desk_1": "t"
    }


def test_plural_type_names_resolve(make_obj: MakeObj) -> None:
    assert match_map([MapEntry("x", "chairs", 0, 0)], [make_obj("Chair_1")]).object_ids == {
        "Chair_1"
    }


def test_without_anchors_the_frame_comes_from_the_correspondences(make_obj: MakeObj) -> None:
    truth = [make_obj("Chair_1", x=0), make_obj("Chair_2", x=4), make_obj("Chair_3", x=4, z=3)]
    # the model's frame: rotated by 90 degrees, origin elsewhere; no anchor in the map
    entries = [
        MapEntry("a", "Chair", 50.0, 54.0),  # Chair_2
        MapEntry("b", "Chair", 47.0, 54.0),  # Chair_3
        MapEntry("c", "Chair", 50.0, 50.0),  # Chair_1
    ]
    m = match_map(entries, truth)
    assert m.label_of == {"Chair_1": "c", "Chair_2": "a", "Chair_3": "b"}
    assert positional_accuracy_score(m, 3) == pytest.approx(1.0, abs=1e-12)


def test_two_anchors_align_a_rotated_map_before_assigning(make_obj: MakeObj) -> None:
    truth = [
        make_obj("Fridge_1", x=0, z=0),
        make_obj("Television_1", x=10, z=0),
        make_obj("Chair_1", x=0, z=5),
        make_obj("Chair_2", x=10, z=5),
    ]
    # The model's frame is rotated by 180 degrees and shifted by (100, 100).
    entries = [
        MapEntry("fridge", "Fridge", 100, 100),
        MapEntry("tv", "Television", 90, 100),
        MapEntry("chair", "Chair", 100, 95),
    ]
    m = match_map(entries, truth)
    assert m.label_of["Chair_1"] == "chair"


def test_one_entry_of_a_repeated_type_takes_the_first_instance(make_obj: MakeObj) -> None:
    truth = [make_obj("Chair_1", x=0), make_obj("Chair_2", x=10)]
    # one point fixes no frame: nothing in the map tells the chairs apart
    assert match_map([MapEntry("a", "Chair", 9.5, 0)], truth).label_of == {"Chair_1": "a"}


def test_entries_beyond_the_instance_count_stay_unmatched(make_obj: MakeObj) -> None:
    truth = [make_obj("Chair_1", x=0), make_obj("Chair_2", x=5)]
    entries = [MapEntry(f"c{i}", "Chair", float(i), 0) for i in range(3)]
    m = match_map(entries, truth)
    assert len(m.pairs) == 2
    assert len(m.unmatched) == 1


def test_an_entry_whose_type_is_all_held_by_carried_labels_matches_nothing(
    make_obj: MakeObj,
) -> None:
    # Found on the mimic cassettes: a duplicate doorway written after the only doorway's
    # label was carried got the all-inf row's argmin, object 0 of another type (ArmChair_1).
    truth = [
        make_obj("ArmChair_1", x=5, z=5),
        make_obj("Doorway_1", x=3, z=0),
        make_obj("Fridge_1", x=0, z=0),
        make_obj("Television_1", x=10, z=0),
    ]
    anchors = [MapEntry("fridge", "Fridge", 0, 0), MapEntry("tv", "Television", 10, 0)]
    first = [*anchors, MapEntry("door", "Doorway", 3, 0), MapEntry("armchair", "ArmChair", 5, 5)]
    second = [*first, MapEntry("passage 2", "Doorway", 3.2, 0)]
    before, after = step_matchings([first, second], truth)
    assert after.label_of == before.label_of
    assert after.unmatched == ("passage 2",)
    assert len(after.object_ids) == len(after.pairs) == 4


def test_a_repeated_label_is_one_more_entry(make_obj: MakeObj) -> None:
    entries = [MapEntry("x", "Chair", 1, 2), MapEntry("x", "Chair", 9, 9)]
    m = match_map(entries, [make_obj("Chair_1")])
    assert m.duplicates == ("x",)
    assert m.entries == 2 and m.unmatched == ("x #2",)
    assert (m.pairs[0].pred_x, m.pairs[0].pred_z) == (1, 2)


def test_a_lone_entry_matches_wherever_it_is_written(make_obj: MakeObj) -> None:
    # one point fixes only a translation: any frame puts it on its object
    m = match_map([MapEntry("f", "Fridge", 1000.0, -1000.0)], [make_obj("Fridge_1")])
    assert m.object_ids == {"Fridge_1"}


def test_an_entry_beyond_the_gate_after_alignment_stands_for_nothing(make_obj: MakeObj) -> None:
    truth = [make_obj("Fridge_1", x=0), make_obj("Television_1", x=6), make_obj("Sink_1", z=4)]
    far = 4 * GATE_M  # no frame puts it within the gate and keeps the others there
    entries = [MapEntry("f", "Fridge", 0, 0), MapEntry("tv", "Television", 6, 0),
               MapEntry("sink", "Sink", 0, 4 + far)]  # fmt: skip
    m = match_map(entries, truth)
    assert m.label_of == {"Fridge_1": "f", "Television_1": "tv"}
    assert m.unmatched == ("sink",)
    assert aec_score(m, 3) == 1.0  # Eq. AEC counts recorded types, not positions


@pytest.mark.parametrize(
    ("entries", "truth_ids"),
    [([], ["Chair_1"]), ([MapEntry("c", "Chair", 0, 0)], []), ([], [])],
    ids=["empty-map", "empty-ground-truth", "both-empty"],
)
def test_empty_inputs_give_no_pairs(
    make_obj: MakeObj, entries: list[MapEntry], truth_ids: list[str]
) -> None:
    assert match_map(entries, [make_obj(i) for i in truth_ids]).pairs == ()


TYPES = ["Chair", "Desk", "Laptop", "Sofa"]  # Sofa never appears in the ground truth


@st.composite
def maps_and_truth(draw: st.DrawFn) -> tuple[list[MapEntry], list[GroundTruthObject]]:
    counts = draw(st.lists(st.integers(0, 3), min_size=3, max_size=3))
    truth = [
        GroundTruthObject(f"{t}_{i + 1}", t, "Office", "salient", draw(coord), draw(coord))
        for t, n in zip(TYPES[:3], counts, strict=True)
        for i in range(n)
    ]
    n_entries = draw(st.integers(0, 8))
    entries = [
        MapEntry(f"e{i}", draw(st.sampled_from(TYPES)), draw(coord), draw(coord))
        for i in range(n_entries)
    ]
    return entries, truth


@given(maps_and_truth())
def test_covered_is_the_aec_numerator_and_bounds_the_pairs(
    case: tuple[list[MapEntry], list[GroundTruthObject]],
) -> None:
    entries, truth = case
    m = match_map(entries, truth)
    expected = sum(
        min(sum(e.object_type == t for e in entries), sum(o.object_type == t for o in truth))
        for t in TYPES
    )
    assert m.covered == expected
    assert len(m.object_ids) == len(m.pairs) <= expected
    assert len(m.pairs) + len(m.unmatched) + len(m.unrecognised) == m.entries


@given(maps_and_truth(), st.sampled_from(["duplicate", "absent-type", "type-at-cap"]))
def test_aec_in_unit_interval_and_never_raised_by_duplicates_or_hallucinations(
    make_obj: MakeObj, case: tuple[list[MapEntry], list[GroundTruthObject]], kind: str
) -> None:
    entries, truth = case
    before = aec_score(match_map(entries, truth), len(truth))
    if before is None:
        assert not truth
        return
    assert 0.0 <= before <= 1.0
    if kind == "duplicate" and entries:
        extra = entries[0]
    elif kind == "type-at-cap":
        full = [
            t for t in TYPES[:3]
            if sum(e.object_type == t for e in entries) >= sum(o.object_type == t for o in truth)
        ]  # fmt: skip
        extra = MapEntry("extra", full[0], 1.0, 1.0) if full else MapEntry("x", "Sofa", 0, 0)
    else:
        extra = MapEntry("ghost", "Sofa", 3.0, 3.0)
    after = aec_score(match_map([*entries, extra], truth), len(truth))
    assert after == before


@given(
    st.lists(st.tuples(coord, coord), min_size=0, max_size=4),
    st.lists(st.tuples(coord, coord), min_size=0, max_size=4),
    st.floats(0, 2 * math.pi),
    coord,
    coord,
    st.integers(2, 12),
)
def test_pa_invariant_under_rigid_motion_and_bounded_by_coverage(
    make_obj: MakeObj,
    chairs: list[tuple[float, float]],
    predicted: list[tuple[float, float]],
    theta: float,
    dx: float,
    dz: float,
    extra_base: int,
) -> None:
    anchors = [make_obj("Fridge_1", KITCHEN, 0, 0), make_obj("Television_1", CONFERENCE, 8, 1)]
    truth = [*anchors, *(make_obj(f"Chair_{i + 1}", x=x, z=z) for i, (x, z) in enumerate(chairs))]
    entries = [
        MapEntry("fridge", "Fridge", 0.3, -0.2),
        MapEntry("tv", "Television", 7.5, 1.4),
        *(MapEntry(f"chair{i}", "Chair", x, z) for i, (x, z) in enumerate(predicted)),
    ]
    c, s = math.cos(theta), math.sin(theta)
    moved = [
        MapEntry(e.label, e.object_type, c * e.x - s * e.z + dx, s * e.x + c * e.z + dz)
        for e in entries
    ]
    g_base = len(truth) + extra_base
    m = match_map(entries, truth)
    pa = positional_accuracy_score(m, g_base)
    pa_moved = positional_accuracy_score(match_map(moved, truth), g_base)
    assert pa is not None and pa_moved is not None
    assert pa_moved == pytest.approx(pa, abs=1e-7)
    assert 0.0 <= pa <= len(m.pairs) / g_base + 1e-12


def test_worked_example_of_the_docstring(make_obj: MakeObj) -> None:
    truth = [make_obj("Desk_1", x=0), make_obj("Desk_2", x=1), make_obj("Door_1", x=-3, z=2)]
    entries = [MapEntry("d1", "Desk", 10, 10), MapEntry("d2", "Desk", 10, 11),
               MapEntry("exit sign", "Door", 10, 25)]  # fmt: skip
    m = match_map(entries, truth)
    assert m.label_of == {"Desk_1": "d1", "Desk_2": "d2"}
    assert m.unmatched == ("exit sign",)


def test_costs_equal_within_the_tie_rounding_break_alike(make_obj: MakeObj) -> None:
    # two chairs exactly as far from the one entry, up to 1e-12 m^2: the first by id wins
    truth = [make_obj("Chair_1", x=-1.0), make_obj("Chair_2", x=1.0 + 1e-13),
             make_obj("Fridge_1", z=3), make_obj("Television_1", z=-3)]  # fmt: skip
    entries = [MapEntry("f", "Fridge", 0, 3), MapEntry("tv", "Television", 0, -3),
               MapEntry("c", "Chair", 0, 0)]  # fmt: skip
    assert match_map(entries, truth).label_of["Chair_1"] == "c"
