"""Serial position: the paper's estimator (Eq. SPE) and our censoring-aware MLE per third."""

from __future__ import annotations

import math
from collections.abc import Callable

import pytest

from pytest_emrd.metrics import EpisodeMetrics, discovery_thirds, efc, serial_position
from pytest_emrd.rooms import OFFICE
from pytest_emrd.trajectory import GroundTruthObject, Trajectory

MakeObj = Callable[..., GroundTruthObject]
MakeTraj = Callable[..., Trajectory]


def _three(make_obj: MakeObj) -> list[GroundTruthObject]:
    # spacings 3 and 5: two chairs of the map fix which two they are
    return [make_obj(f"Chair_{i}", x=float(i * i)) for i in (1, 2, 3)]


def _held(*labels: int) -> dict[str, tuple[str, float, float]]:
    return {f"c{i}": ("Chair", float(i * i), 0.0) for i in labels}


def test_worked_example_events_and_a_censored_middle(
    make_obj: MakeObj, make_traj: MakeTraj
) -> None:
    """Chair_1..3 seen once each at steps 1-3. Chair_1 leaves view at 2 and is dropped at 4
    (event, 3 steps); Chair_3 leaves at 4, dropped at 6 (event, 3); Chair_2 leaves at 3 and
    is still held when the episode ends at 6 (censored, 4)."""
    steps = [
        (OFFICE, ["Chair_1"], _held(1)),
        (OFFICE, ["Chair_2"], _held(1, 2)),
        (OFFICE, ["Chair_3"], _held(1, 2, 3)),
        (OFFICE, [], _held(2, 3)),
        (OFFICE, [], _held(2, 3)),
        (OFFICE, [], _held(2)),
    ]
    sp = serial_position([make_traj(_three(make_obj), steps)])
    assert (sp.early, sp.middle, sp.late) == (3.0, 4.0, 3.0)
    assert (sp.mle_early, sp.mle_middle, sp.mle_late) == (3.0, math.inf, 3.0)
    assert (sp.spells, sp.events) == ((1, 1, 1), (1, 0, 1))


def test_perfect_memory_biases_the_paper_estimator_not_the_mle(
    make_obj: MakeObj, make_traj: MakeTraj
) -> None:
    """Nothing is ever forgotten, yet censoring at the end makes the paper's means fall
    E > M > L; the MLE says what happened: no forgetting in any third (inf)."""
    steps = [
        (OFFICE, ["Chair_1"], _held(1)),
        (OFFICE, ["Chair_2"], _held(1, 2)),
        (OFFICE, ["Chair_3"], _held(1, 2, 3)),
        (OFFICE, [], _held(1, 2, 3)),
    ]
    sp = serial_position([make_traj(_three(make_obj), steps)])
    assert sp.early is not None and sp.middle is not None and sp.late is not None
    assert sp.early > sp.middle > sp.late
    assert (sp.mle_early, sp.mle_middle, sp.mle_late) == (math.inf, math.inf, math.inf)


def test_no_spell_in_a_third_gives_none(make_obj: MakeObj, make_traj: MakeTraj) -> None:
    steps = [(OFFICE, ["Chair_1", "Chair_2", "Chair_3"], _held(1, 2, 3))]
    sp = serial_position([make_traj(_three(make_obj), steps)])
    assert (sp.mle_early, sp.mle_middle, sp.mle_late) == (None, None, None)
    assert (sp.early, sp.middle, sp.late) == (None, None, None)
    assert serial_position([]).mle_early is None


def test_mle_pools_every_first_spell_by_third(small_grid_metrics: list[EpisodeMetrics]) -> None:
    """Against a direct computation: each first spell goes to its episode's third."""
    sp = serial_position(small_grid_metrics)
    pooled: list[tuple[list[int], list[bool]]] = [([], []), ([], []), ([], [])]
    for m in small_grid_metrics:
        third = discovery_thirds(sum(m.mapped_by_category.values()))
        for s in m.ttf_spells:
            durations, events = pooled[third[s.discovery_rank - 1]]
            durations.append(s.duration)
            events.append(s.forgotten)
    expected = tuple(efc(d, e) for d, e in pooled)
    assert (sp.mle_early, sp.mle_middle, sp.mle_late) == pytest.approx(expected)
    assert sum(sp.spells) == sum(len(m.ttf_spells) for m in small_grid_metrics)
    assert sum(sp.events) == sum(m.forget_events for m in small_grid_metrics)


@pytest.mark.parametrize(
    ("n", "sizes"),
    [(30, (10, 10, 10)), (10, (4, 3, 3)), (2, (1, 1, 0)), (0, (0, 0, 0))],
    ids=["30", "10", "2", "0"],
)
def test_discovery_thirds_sizes(n: int, sizes: tuple[int, int, int]) -> None:
    third = discovery_thirds(n)
    assert tuple(int((third == b).sum()) for b in range(3)) == sizes
    assert list(third) == sorted(third)
