"""Per-episode scores: PA, AEC, TE, FPSG, serial-position bins, SIR (worked examples, edges)."""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from scipy.optimize import minimize_scalar

from pytest_emrd.metrics import (
    aec_score,
    episode_metrics,
    grounding_scores,
    hallucination_score,
    match_map,
    pa_coverage,
    positional_accuracy_score,
    precision_score,
    serial_position_bins,
    te_score,
)
from pytest_emrd.rooms import CONFERENCE, ENTRANCE, KITCHEN, OFFICE
from pytest_emrd.trajectory import GroundTruthObject, MapEntry, Trajectory

MakeObj = Callable[..., GroundTruthObject]
MakeTraj = Callable[..., Trajectory]


def _oracle_rmse(pred: np.ndarray, true: np.ndarray) -> float:
    """Brute-force rigid alignment: best angle by bounded search, translation by centroids."""

    def rmse(theta: float) -> float:
        rot = np.array([[math.cos(theta), -math.sin(theta)], [math.sin(theta), math.cos(theta)]])
        aligned = (pred - pred.mean(0)) @ rot.T + true.mean(0)
        return float(np.sqrt(np.mean(np.sum((aligned - true) ** 2, axis=1))))

    starts = np.linspace(-math.pi, math.pi, 73)
    best = min(starts, key=rmse)
    res = minimize_scalar(rmse, bounds=(best - 0.1, best + 0.1), method="bounded",
                          options={"xatol": 1e-12})  # fmt: skip
    return min(float(res.fun), rmse(best))


def test_pa_appendix_b_example_three_of_five_mapped_perfectly(make_obj: MakeObj) -> None:
    # |G_base| = 5; A, B, C are mapped in a frame rotated by 90 degrees and shifted; D, E missed.
    truth = [make_obj("Desk_1", x=0, z=0), make_obj("Fridge_1", x=4, z=0),
             make_obj("Sink_1", x=0, z=3), make_obj("Stool_1", x=9, z=9),
             make_obj("Sofa_1", x=-9, z=9)]  # fmt: skip
    entries = [MapEntry("A", "Desk", 5, 5), MapEntry("B", "Fridge", 5, 9),
               MapEntry("C", "Sink", 2, 5)]  # fmt: skip
    m = match_map(entries, truth)
    assert len(m.pairs) == 3
    assert positional_accuracy_score(m, 5) == pytest.approx(3 / 5, abs=1e-12)


def test_pa_charges_entries_that_stand_for_nothing(make_obj: MakeObj) -> None:
    # the docstring's example: Appendix B's map plus 3 entries of its types far from anything
    truth = [make_obj("Desk_1", x=0, z=0), make_obj("Fridge_1", x=4, z=0),
             make_obj("Sink_1", x=0, z=3), make_obj("Stool_1", x=9, z=9),
             make_obj("Sofa_1", x=-9, z=9)]  # fmt: skip
    entries = [MapEntry("A", "Desk", 5, 5), MapEntry("B", "Fridge", 5, 9),
               MapEntry("C", "Sink", 2, 5), MapEntry("x", "Desk", 40, 40),
               MapEntry("y", "Desk", 41, 40), MapEntry("z", "Desk", 40, 41)]  # fmt: skip
    m = match_map(entries, truth)
    assert (len(m.pairs), len(m.unmatched)) == (3, 3)
    assert positional_accuracy_score(m, 5) == 0.0
    assert precision_score(m) == 0.5


@pytest.mark.parametrize(
    ("matched", "unmatched", "g_base", "coverage"),
    [(3, 0, 5, 0.6), (40, 1, 41, 40 / 41), (40, 2, 41, 40 / 41), (40, 3, 41, 39 / 41),
     (41, 959, 41, 0.0), (0, 0, 5, 0.0), (3, 0, 0, 0.0)],
    ids=["paper", "one-free", "two-free", "third-charged", "spray", "nothing", "no-g-base"],
)  # fmt: skip
def test_pa_coverage_worked_examples(
    matched: int, unmatched: int, g_base: int, coverage: float
) -> None:
    assert pa_coverage(matched, unmatched, g_base) == pytest.approx(coverage)


@given(st.integers(0, 60), st.integers(0, 60), st.integers(1, 60), st.integers(1, 60))
def test_pa_coverage_never_rises_with_unmatched_entries(
    matched: int, unmatched: int, g_base: int, extra: int
) -> None:
    before = pa_coverage(matched, unmatched, g_base)
    assert 0.0 <= before <= 1.0
    assert pa_coverage(matched, unmatched + extra, g_base) <= before


def test_precision_and_hallucination_rate_worked_example(make_obj: MakeObj) -> None:
    # 2 desks and a chair mapped, a third desk the office lacks, 2 sofas it lacks
    truth = [make_obj("Desk_1", x=0), make_obj("Desk_2", x=3), make_obj("Chair_1", z=2)]
    entries = [MapEntry("d1", "Desk", 0, 0), MapEntry("d2", "Desk", 3, 0),
               MapEntry("d3", "Desk", 6, 0), MapEntry("c", "Chair", 0, 2),
               MapEntry("s1", "Sofa", 1, 1), MapEntry("s2", "Sofa", 2, 1)]  # fmt: skip
    m = match_map(entries, truth)
    assert precision_score(m) == pytest.approx(3 / 6)
    assert hallucination_score(m) == pytest.approx(3 / 6)  # d3 and the sofas stand for nothing
    assert precision_score(match_map([], truth)) is None
    assert hallucination_score(match_map([], truth)) is None


WRITTEN = st.tuples(st.sampled_from(["Desk", "Chair", "Sofa", "ghost"]), st.floats(-5, 5),
                    st.floats(-5, 5))  # fmt: skip


@given(st.lists(WRITTEN, min_size=1, max_size=10))
def test_precision_and_hallucination_rate_add_up_to_one(
    make_obj: MakeObj, written: list[tuple[str, float, float]]
) -> None:
    truth = [make_obj("Desk_1", x=0), make_obj("Desk_2", x=3), make_obj("Chair_1", z=2)]
    m = match_map([MapEntry(f"e{i}", *w) for i, w in enumerate(written)], truth)
    p, h = precision_score(m), hallucination_score(m)
    assert p is not None and h is not None
    assert p + h == pytest.approx(1.0)
    ghost = match_map([*(MapEntry(f"e{i}", *w) for i, w in enumerate(written)),
                       MapEntry("ghost", "ghost", 0, 0)], truth)  # fmt: skip
    assert positional_accuracy_score(ghost, 3) == positional_accuracy_score(m, 3)
    assert hallucination_score(ghost) > h or h == 1.0


def test_pa_with_residual_matches_a_brute_force_procrustes(make_obj: MakeObj) -> None:
    truth = [make_obj("Desk_1", x=0, z=0), make_obj("Fridge_1", x=4, z=0),
             make_obj("Sink_1", x=0, z=3)]  # fmt: skip
    entries = [MapEntry("A", "Desk", 1, 1), MapEntry("B", "Fridge", 1.3, 5.2),
               MapEntry("C", "Sink", -2.1, 0.8)]  # fmt: skip
    pred = np.array([[1, 1], [1.3, 5.2], [-2.1, 0.8]])
    true = np.array([[0, 0], [4, 0], [0, 3]], dtype=float)
    l_gt = math.sqrt(50 / 9)  # RMS spread of A, B, C: (25 + 73 + 52) / 27 = 50 / 9
    expected = math.exp(-_oracle_rmse(pred, true) / l_gt) * 3 / 5
    pa = positional_accuracy_score(match_map(entries, truth), 5)
    assert pa == pytest.approx(expected, rel=1e-9)


@pytest.mark.parametrize(
    ("entries", "g_base", "expected"),
    [
        ([], 4, 0.0),
        ([MapEntry("a", "Desk", 40, -3)], 4, 0.25),
        ([MapEntry("a", "Desk", 0, 0)], 0, None),
    ],
    ids=["no-match-gives-0", "single-object-aligns-perfectly", "empty-G_base-undefined"],
)
def test_pa_edge_cases(
    make_obj: MakeObj, entries: list[MapEntry], g_base: int, expected: float | None
) -> None:
    assert positional_accuracy_score(match_map(entries, [make_obj("Desk_1")]), g_base) == expected


def test_pa_coincident_ground_truth_with_residual_scores_zero(make_obj: MakeObj) -> None:
    truth = [make_obj("Desk_1"), make_obj("Sink_1")]
    entries = [MapEntry("a", "Desk", 0, 0), MapEntry("b", "Sink", 3, 0)]
    assert positional_accuracy_score(match_map(entries, truth), 2) == 0.0


def test_pa_coverage_factor_is_capped_at_one(make_obj: MakeObj) -> None:
    truth = [make_obj("Desk_1"), make_obj("Sink_1", x=2)]
    entries = [MapEntry("a", "Desk", 0, 0), MapEntry("b", "Sink", 2, 0)]
    assert positional_accuracy_score(match_map(entries, truth), 1) == 1.0


@pytest.mark.parametrize(
    ("n_entries", "n_objects", "expected"),
    [(0, 3, 0.0), (1, 1, 1.0), (2, 4, 0.5), (0, 0, None)],
    ids=["empty-map", "single-object", "half", "no-ground-truth"],
)
def test_aec_edge_cases(
    make_obj: MakeObj, n_entries: int, n_objects: int, expected: float | None
) -> None:
    truth = [make_obj(f"Chair_{i + 1}", x=float(i)) for i in range(n_objects)]
    entries = [MapEntry(f"c{i}", "Chair", float(i), 0) for i in range(n_entries)]
    assert aec_score(match_map(entries, truth), n_objects) == expected


@pytest.mark.parametrize(
    ("n_steps", "status", "expected"),
    [(5, "terminated", 4), (50, "budget", 50), (1, "terminated", 0), (0, "budget", 0)],
    ids=["term-not-counted", "budget", "term-first-step", "no-steps"],
)
def test_te(make_traj: MakeTraj, n_steps: int, status: str, expected: int) -> None:
    traj = make_traj([], [(OFFICE, [], {})] * n_steps, status=status)
    assert te_score(traj) == expected


def _fpsg_world(make_obj: MakeObj) -> list[GroundTruthObject]:
    return (
        [make_obj(f"Chair_{i + 1}", CONFERENCE, x=float(i), z=10) for i in range(10)]
        + [make_obj(f"ArmChair_{i + 1}", ENTRANCE, x=float(i), z=-10) for i in range(2)]
        + [make_obj(f"Desk_{i + 1}", OFFICE, x=float(i), z=0) for i in range(8)]
    )


@pytest.mark.parametrize(
    ("chosen", "mapped", "local", "glob"),
    [(CONFERENCE, 5, 0.5, 0.25), (ENTRANCE, 2, 1.0, 0.1)],
    ids=["agent-A-dense-conference", "agent-B-sparse-entrance"],
)
def test_fpsg_appendix_b_agents(
    make_obj: MakeObj, make_traj: MakeTraj, chosen: str, mapped: int, local: float, glob: float
) -> None:
    truth = _fpsg_world(make_obj)
    in_room = [o for o in truth if o.room == chosen][:mapped]
    cog = {o.object_id: (o.object_type, o.x, o.z) for o in in_room}
    traj = make_traj(truth, [(chosen, [o.object_id for o in truth], cog)], chosen=chosen)
    g = grounding_scores(traj, match_map(traj.final_map, truth))
    assert (g.fpsg_local, g.fpsg_global) == (pytest.approx(local), pytest.approx(glob))
    assert g.never_visited is False and g.any_bias is False


def test_fpsg_unseen_inventory_entry_is_no_evidence(make_obj: MakeObj, make_traj: MakeTraj) -> None:
    truth = _fpsg_world(make_obj)
    traj = make_traj(
        truth, [(OFFICE, ["Desk_1"], {"tv": ("ArmChair", 0.0, -10.0)})], chosen=ENTRANCE
    )
    g = grounding_scores(traj, match_map(traj.final_map, truth))
    assert (g.fpsg_local, g.fpsg_global, g.never_visited, g.any_bias) == (0.0, 0.0, True, True)


def test_fpsg_counts_doorways_as_the_paper_does_and_reports_the_variant_without(
    make_obj: MakeObj, make_traj: MakeTraj
) -> None:
    """A doorway filed under the Entrance, seen and mapped from the Office: in O_F by the
    paper's definition; left out by the doorway-free variant (O_F = the two armchairs)."""
    truth = [
        *_fpsg_world(make_obj),
        make_obj("Doorway_1", ENTRANCE, x=0.0, z=-5.0, category="landmark"),
    ]
    cog = {"Doorway_1": ("Doorway", 0.0, -5.0)}
    traj = make_traj(truth, [(OFFICE, ["Desk_1", "Doorway_1"], cog)], chosen=ENTRANCE)
    g = grounding_scores(traj, match_map(traj.final_map, truth))
    assert (g.fpsg_local, g.fpsg_global, g.never_visited, g.any_bias) == (1 / 3, 0.5, True, False)
    assert (g.fpsg_local_ex_doorways, g.fpsg_global_ex_doorways) == (0.0, 0.0)
    armchair = {**cog, "ArmChair_1": ("ArmChair", 0.0, -10.0)}
    traj = make_traj(truth, [(OFFICE, ["ArmChair_1", "Doorway_1"], armchair)], chosen=ENTRANCE)
    g = grounding_scores(traj, match_map(traj.final_map, truth))
    assert (g.fpsg_local, g.fpsg_global, g.any_bias) == (2 / 3, 1.0, False)
    assert (g.fpsg_local_ex_doorways, g.fpsg_global_ex_doorways) == (0.5, 0.5)


def test_fpsg_room_of_doorways_only_has_no_local_value_without_doorways(
    make_obj: MakeObj, make_traj: MakeTraj
) -> None:
    truth = [*_fpsg_world(make_obj), make_obj("Doorway_1", KITCHEN, category="landmark")]
    traj = make_traj(truth, [(OFFICE, ["Doorway_1"], {})], chosen=KITCHEN)
    g = grounding_scores(traj, match_map(traj.final_map, truth))
    assert (g.fpsg_local, g.fpsg_global, g.any_bias) == (0.0, 0.0, True)
    assert g.fpsg_local_ex_doorways is None


@pytest.mark.parametrize(
    ("chosen", "visible", "missing"),
    [(None, ["Desk_1"], {"fpsg_local", "fpsg_global", "never_visited", "any_bias"}),
     (KITCHEN, ["Desk_1"], {"fpsg_local"}),
     (OFFICE, [], {"fpsg_global"})],
    ids=["no-chosen-room", "room-without-objects", "nothing-observed"],
)  # fmt: skip
def test_fpsg_undefined_cases_carry_reasons(
    make_obj: MakeObj, make_traj: MakeTraj, chosen: str | None, visible: list[str],
    missing: set[str],
) -> None:  # fmt: skip
    truth = _fpsg_world(make_obj)
    traj = make_traj(truth, [(OFFICE, visible, {})], chosen=chosen)
    g = grounding_scores(traj, match_map(traj.final_map, truth))
    assert set(g.reasons) == missing
    assert all(getattr(g, name) is None for name in missing)


@given(st.integers(1, 12), st.integers(0, 12), st.integers(0, 12), st.integers(0, 24))
def test_fpsg_local_at_least_global_when_room_no_larger_than_observed(
    make_obj: MakeObj, make_traj: MakeTraj, in_room: int, mapped: int, others: int, seen: int
) -> None:
    truth = [make_obj(f"Chair_{i + 1}", CONFERENCE, x=float(i)) for i in range(in_room)] + [
        make_obj(f"Desk_{i + 1}", OFFICE, x=float(i), z=5) for i in range(others)
    ]
    visible = [o.object_id for o in truth][: max(seen, 1)]
    cog = {o.object_id: (o.object_type, o.x, o.z) for o in truth[: min(mapped, in_room)]}
    traj = make_traj(truth, [(CONFERENCE, visible, cog)], chosen=CONFERENCE)
    g = grounding_scores(traj, match_map(traj.final_map, truth))
    assert g.fpsg_local is not None and g.fpsg_global is not None
    assert 0.0 <= g.fpsg_global <= 1.0 and 0.0 <= g.fpsg_local <= 1.0
    if in_room <= len(visible):
        assert g.fpsg_local >= g.fpsg_global


def test_serial_position_appendix_b_example() -> None:
    ttf = [15.0] * 10 + [5.0] * 10 + [12.0] * 10
    assert serial_position_bins(ttf) == (15.0, 5.0, 12.0)


@pytest.mark.parametrize(
    ("ttf", "expected"),
    [
        ([1, 1, 1, 1, 2, 2, 2, 3, 3, 3], (1.0, 2.0, 3.0)),
        ([4.0, None, 2.0], (4.0, None, 2.0)),
        ([7.0], (7.0, None, None)),
        ([], (None, None, None)),
    ],
    ids=["ten-split-4-3-3", "bin-without-ttf", "single-object", "nothing-discovered"],
)
def test_serial_position_bins_edge_cases(
    ttf: list[float | None], expected: tuple[float | None, ...]
) -> None:
    assert serial_position_bins(ttf) == expected


def test_sir_counts_objects_recognised_by_the_same_label(
    make_obj: MakeObj, make_traj: MakeTraj
) -> None:
    truth = [make_obj("Desk_1", OFFICE, 0, 0), make_obj("Desk_2", OFFICE, 3, 0),
             make_obj("Fridge_1", KITCHEN, 0, -6)]  # fmt: skip
    first = {"d1": ("Desk", 0.0, 0.0), "d2": ("Desk", 3.0, 0.0)}
    steps = [
        (OFFICE, ["Desk_1", "Desk_2"], first),
        (KITCHEN, ["Fridge_1"], {**first, "f": ("Fridge", 0.0, -6.0)}),
        (OFFICE, ["Desk_1", "Desk_2"],
         {"d1": ("Desk", 0.0, 0.0), "new desk": ("Desk", 3.0, 0.0), "f": ("Fridge", 0.0, -6.0)}),
    ]  # fmt: skip
    m = episode_metrics(make_traj(truth, steps))
    assert m.aec == 1.0
    assert m.sir == pytest.approx(0.5)


def test_sir_without_re_entry_is_none_with_reason(make_obj: MakeObj, make_traj: MakeTraj) -> None:
    m = episode_metrics(make_traj([make_obj("Desk_1")], [(OFFICE, ["Desk_1"], {})] * 3))
    assert m.sir is None
    assert m.reasons["sir"] == "no room was re-entered"


def _reentry(make_obj: MakeObj, make_traj: MakeTraj, written: dict, motion=None) -> Trajectory:
    """Office with three desks: d1, d2 mapped on the first visit, the kitchen's fridge, then
    on re-entry d1 and d2 kept, Desk_3 mapped for the first time (``third desk``) and the
    entries ``written`` added (spawn-frame positions; ``motion`` moves every position)."""
    truth = [make_obj("Desk_1", OFFICE, 0, 0), make_obj("Desk_2", OFFICE, 3, 0),
             make_obj("Desk_3", OFFICE, 6, 2), make_obj("Fridge_1", KITCHEN, 0, -6)]  # fmt: skip

    def place(entries: dict) -> dict:
        if motion is None:
            return entries
        return {lb: (tp, *motion(x, z)) for lb, (tp, x, z) in entries.items()}

    first = {"d1": ("Desk", 0.0, 0.0), "d2": ("Desk", 3.0, 0.0)}
    seen = {**first, "f": ("Fridge", 0.0, -6.0)}
    back = {**seen, "third desk": ("Desk", 6.0, 2.1), **written}
    steps = [
        (OFFICE, ["Desk_1", "Desk_2"], place(first)),
        (KITCHEN, ["Fridge_1"], place(seen)),
        (OFFICE, ["Desk_1", "Desk_2", "Desk_3"], place(back)),
    ]
    return make_traj(truth, steps)


#: Desk_2 written again on re-entry, 0.22 m from where d2 (still held) puts it.
COPY = {"desk again": ("Desk", 3.1, 0.2)}


@pytest.mark.parametrize(
    ("written", "expected"),
    [(COPY, 0.5), ({"lamp": ("Lamp", 3.0, 0.0)}, 1.0), ({}, 1.0)],
    ids=["copy-of-a-held-object", "hallucination-copies-nothing", "no-copy"],
)
def test_sir_leaves_out_objects_written_again_on_re_entry(
    make_obj: MakeObj, make_traj: MakeTraj, written: dict, expected: float
) -> None:
    # M_first = {Desk_1, Desk_2}, both keep their labels. "desk again" lies nearest Desk_2,
    # which d2 holds: a copy, so Desk_2 was not deduplicated (1/2). "third desk" lies nearest
    # Desk_3, which no other label holds: newly mapped, not a copy. "lamp" has no layout type.
    m = episode_metrics(_reentry(make_obj, make_traj, written))
    assert m.aec == 1.0
    assert m.sir == pytest.approx(expected, abs=1e-15)


@given(
    theta=st.floats(-math.pi, math.pi),
    tx=st.floats(-1e3, 1e3),
    tz=st.floats(-1e3, 1e3),
)
def test_sir_copies_do_not_depend_on_the_models_frame(
    make_obj: MakeObj, make_traj: MakeTraj, theta: float, tx: float, tz: float
) -> None:
    c, s = math.cos(theta), math.sin(theta)

    def motion(x: float, z: float) -> tuple[float, float]:
        return c * x - s * z + tx, s * x + c * z + tz

    moved = _reentry(make_obj, make_traj, COPY, motion)
    assert episode_metrics(moved).sir == pytest.approx(0.5, abs=1e-9)
