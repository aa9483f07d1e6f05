"""Grounded credit (issue 34): entries of objects the frames never showed earn nothing."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import pytest
import yaml
from hypothesis import given
from hypothesis import strategies as st

from pytest_emrd.metrics import GATE_METRICS, episode_metrics, grounded_scores, match_map
from pytest_emrd.trajectory import GroundTruthObject, Trajectory
from pytest_emrd.world import paper_office

MakeTraj = Callable[..., Trajectory]
ROOT = Path(__file__).resolve().parents[2]
OFFICE = [
    GroundTruthObject(o.object_id, o.object_type, o.room, o.category, o.x, o.z)
    for o in paper_office().objects
]
WHOLE = {o.object_id: (o.object_type, o.x, o.z) for o in OFFICE}
#: What two frames in the office's Office room might show.
SHOWN = ("Desk_1", "Chair_1", "Doorway_1")


def test_the_whole_office_written_in_a_two_step_episode_is_ungrounded(
    make_traj: MakeTraj,
) -> None:
    shown = [oid for oid in SHOWN if oid in WHOLE]
    traj = make_traj(OFFICE, [("Office", shown[:1], WHOLE), ("Office", shown[1:], WHOLE)])
    m = episode_metrics(traj)
    assert m.aec == m.pa == m.precision == 1.0  # the paper's scores cannot tell
    assert m.grounded_aec <= len(shown) / len(OFFICE)
    assert m.ungrounded_rate >= 0.5
    estimate = GATE_METRICS["ungrounded_rate"].compute([m])
    shipped = yaml.safe_load((ROOT / "thresholds.yaml").read_text(encoding="utf-8"))
    bounds = {
        (model, c): cells[c]["ungrounded_rate"] for model, cells in shipped.items() for c in cells
    }
    assert len(bounds) == 7 * 3 + 3 + 1  # every condition of every model holds the gate
    assert all(estimate.value > b["max"] for b in bounds.values())


def test_worked_example_entry_written_before_its_object_was_shown(make_traj: MakeTraj) -> None:
    # step 1 shows Desk_1 and the map holds the desk and the fridge; the fridge is shown at
    # step 2: the fridge's entry appeared before it, the chair's never was shown
    objects = [o for o in OFFICE if o.object_id in ("Desk_1", "Fridge_1", "Chair_1")]
    entries = {o.object_id: WHOLE[o.object_id] for o in objects}
    traj = make_traj(
        OFFICE,
        [
            ("Office", ["Desk_1"], {k: entries[k] for k in ("Desk_1", "Fridge_1")}),
            ("Kitchen", ["Fridge_1"], entries),
        ],
    )
    final = match_map(traj.final_map, traj.ground_truth.objects)
    grounded_aec, rate, reasons = grounded_scores(traj, final)
    assert rate == pytest.approx(2 / 3)  # Fridge_1 (written at step 1) and Chair_1
    assert grounded_aec == pytest.approx(1 / len(OFFICE))
    assert reasons == {}


def test_an_entry_written_when_its_object_is_shown_is_grounded(make_traj: MakeTraj) -> None:
    steps = [("Office", [oid], {oid: WHOLE[oid]}) for oid in ("Desk_1", "Chair_1")]
    steps.append(("Office", [], {oid: WHOLE[oid] for oid in ("Desk_1", "Chair_1")}))
    m = episode_metrics(make_traj(OFFICE, steps))
    assert m.ungrounded_rate == 0.0
    assert m.grounded_aec == m.aec == pytest.approx(2 / len(OFFICE))


@pytest.mark.parametrize(
    ("steps", "grounded_aec", "rate"),
    [
        ([], 0.0, None),
        ([("Office", [], {})], 0.0, None),
        ([("Office", [], {"ghost": ("Sofa", 0.0, 0.0)})], 0.0, None),
    ],
    ids=["no-step", "empty-map", "nothing-matched"],
)
def test_edge_cases(make_traj: MakeTraj, steps, grounded_aec, rate) -> None:
    traj = make_traj(OFFICE, steps)
    final = match_map(traj.final_map, traj.ground_truth.objects)
    got_aec, got_rate, reasons = grounded_scores(traj, final)
    assert (got_aec, got_rate) == (grounded_aec, rate)
    assert "ungrounded_rate" in reasons


def test_no_object_gives_none(make_traj: MakeTraj) -> None:
    traj = make_traj([], [("Office", [], {"desk": ("Desk", 0.0, 0.0)})])
    got = grounded_scores(traj, match_map(traj.final_map, []))
    assert got[0] is None and set(got[2]) == {"grounded_aec", "ungrounded_rate"}


@given(st.lists(st.sampled_from(sorted(WHOLE)), max_size=12, unique=True), st.integers(1, 4))
def test_grounded_aec_never_exceeds_aec_and_the_rate_is_a_share(
    make_traj: MakeTraj, shown: list[str], split: int
) -> None:
    written = {oid: WHOLE[oid] for oid in sorted(WHOLE)[: 3 * split]}
    traj = make_traj(OFFICE, [("Office", shown[:split], {}), ("Office", shown[split:], written)])
    m = episode_metrics(traj)
    assert m.grounded_aec <= m.aec
    assert 0.0 <= m.ungrounded_rate <= 1.0
    assert m.ungrounded_rate == pytest.approx(len(set(written) - set(shown)) / len(written))


@pytest.mark.slow
def test_the_committed_scout_maps_only_what_it_was_shown(committed: list[Trajectory]) -> None:
    for traj in committed:
        m = episode_metrics(traj)
        assert m.ungrounded_rate == 0.0
        assert m.grounded_aec == m.aec
