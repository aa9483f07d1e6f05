"""Maps written the way a VLM writes them, or to game the score (issue 23's scenarios).

Each test reproduces one defect of the issue on the committed scout episodes (replayed
offline) or on a hand-built office, and pins what the metrics now report.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pytest_emrd.metrics import (
    EpisodeMetrics,
    episode_metrics,
    match_map,
    positional_accuracy_score,
    reframe,
)
from pytest_emrd.trajectory import GroundTruthObject, MapEntry, Trajectory

MakeObj = Callable[..., GroundTruthObject]
MakeTraj = Callable[..., Trajectory]


def _with_maps(
    traj: Trajectory, change: Callable[[int, tuple[MapEntry, ...]], tuple]
) -> Trajectory:
    """``traj`` with every step's map replaced by ``change(step index, map)``."""
    steps = tuple(
        dataclasses.replace(s, cognitive_map=tuple(change(i, s.cognitive_map)))
        for i, s in enumerate(traj.steps)
    )
    return dataclasses.replace(traj, steps=steps)


def _memory(m: EpisodeMetrics) -> tuple:
    return m.spells, m.memory_strength, m.forget_events, m.serial_position, m.sir


# --- 1. the terminal map is scored on its own -----------------------------------------------


def _office(make_obj: MakeObj) -> list[GroundTruthObject]:
    return [
        make_obj("Fridge_1", x=0, z=0), make_obj("Television_1", x=6, z=0),
        make_obj("Desk_1", x=2, z=3), make_obj("Desk_2", x=2.6, z=3),
        make_obj("Chair_1", x=4, z=4), make_obj("Chair_2", x=5, z=1),
    ]  # fmt: skip


def test_desks_swapped_at_step_one_do_not_lower_the_corrected_final_map(
    make_obj: MakeObj, make_traj: MakeTraj
) -> None:
    # Issue: swapped at step 1, corrected at step 2, PA 0.548 against 0.9997 for the same
    # final map on its own (the step-1 pairing was carried and never checked again).
    truth = _office(make_obj)
    right = {
        "fridge": ("Fridge", 0, 0),
        "tv": ("Television", 6, 0),
        "desk a": ("Desk", 2, 3),
        "desk b": ("Desk", 2.6, 3),
        "chair a": ("Chair", 4, 4),
        "chair b": ("Chair", 5, 1),
    }
    swapped = {**right, "desk a": ("Desk", 2.6, 3), "desk b": ("Desk", 2, 3)}  # fmt: skip
    with_history = episode_metrics(make_traj(truth, [("Office", [], swapped),
                                                     ("Office", [], right)]))  # fmt: skip
    alone = episode_metrics(make_traj(truth, [("Office", [], right)]))
    assert with_history.pa == alone.pa == pytest.approx(1.0)


@st.composite
def histories(draw: st.DrawFn) -> list[dict[str, tuple[str, float, float]]]:
    coord = st.floats(-8, 8, allow_nan=False)
    kinds = st.sampled_from(["Fridge", "Television", "Desk", "Chair", "Sofa"])
    step = st.dictionaries(st.sampled_from([f"e{i}" for i in range(8)]),
                           st.tuples(kinds, coord, coord), max_size=8)  # fmt: skip
    return draw(st.lists(step, min_size=1, max_size=4))


@settings(max_examples=60, deadline=None)
@given(histories())
def test_terminal_pa_and_aec_depend_on_the_terminal_map_alone(
    make_obj: MakeObj, make_traj: MakeTraj, maps: list[dict[str, tuple[str, float, float]]]
) -> None:
    truth = _office(make_obj)
    full = episode_metrics(make_traj(truth, [("Office", [], m) for m in maps]))
    last = episode_metrics(make_traj(truth, [("Office", [], maps[-1])]))
    assert (full.pa, full.aec, full.precision) == (last.pa, last.aec, last.precision)


# --- 2. forgetting is what the model did --------------------------------------------------


@pytest.mark.slow
def test_a_mirrored_or_noisier_map_without_a_dropped_label_forgets_nothing(
    committed: list[Trajectory],
) -> None:
    # Issue: mirroring a scout map (no label dropped) made EFC finite in 197 of 240 episodes.
    rng = np.random.default_rng(5)
    for traj in committed:
        mirrored = episode_metrics(reframe(traj, 0.7, 3.0, -2.0, mirror=True))
        noisy = episode_metrics(_with_maps(traj, lambda _, m: tuple(
            dataclasses.replace(e, x=e.x + rng.normal(0, 1.0), z=e.z + rng.normal(0, 1.0))
            for e in m)))  # fmt: skip
        for m in (mirrored, noisy):
            assert m.forget_events == 0
            assert not any(s.forgotten for s in m.spells)


def test_a_dropped_label_is_forgotten_however_the_rest_is_rematched(
    make_obj: MakeObj, make_traj: MakeTraj
) -> None:
    truth = _office(make_obj)
    full = {"fridge": ("Fridge", 0, 0), "tv": ("Television", 6, 0), "desk": ("Desk", 2, 3),
            "chair": ("Chair", 4, 4)}  # fmt: skip
    no_desk = {k: v for k, v in full.items() if k != "desk"}
    relabelled = {**full, "desk": ("Television", 2, 3)}  # relabelled away: not a desk any more
    for later in (no_desk, relabelled):
        traj = make_traj(truth, [("Office", ["Desk_1"], full), ("Office", [], full),
                                 ("Office", [], later)])  # fmt: skip
        (spell,) = [s for s in episode_metrics(traj).spells if s.object_id == "Desk_1"]
        assert (spell.start, spell.duration, spell.forgotten) == (2, 2, True)


# --- 3. one hallucinated landmark cannot capture the frame --------------------------------


@pytest.mark.slow
@pytest.mark.parametrize("written_type", ["exit sign", "Door"], ids=["as-written", "as-a-door"])
@pytest.mark.parametrize("episodes", ["committed", "sparse_early"])
def test_one_hallucinated_landmark_moves_pa_by_at_most_0_02_and_no_memory_metric(
    request: pytest.FixtureRequest, episodes: str, written_type: str
) -> None:
    # Issue: an "exit sign" read as the office's only Door became an anchor: PA 0.9997 -> 0.743,
    # EFC infinity -> 44. On a map of a few entries it fits as well as the real ones and moved
    # discovery ranks (serial position) in the sparse_early episodes.
    moved, trajs = set(), request.getfixturevalue(episodes)
    for traj in trajs:
        final = traj.steps[-1].cognitive_map
        spot = (final[0].x + 4.0, final[0].z - 3.0)  # somewhere in the model's frame
        sign = MapEntry("exit sign", written_type, *spot)
        with_sign = _with_maps(traj, lambda i, m, sign=sign: (*m, sign) if i >= 1 else m)
        base, hallucinated = episode_metrics(traj), episode_metrics(with_sign)
        assert base.pa is not None and hallucinated.pa is not None
        assert abs(hallucinated.pa - base.pa) <= 0.02
        if _memory(hallucinated) != _memory(base):
            moved.add((traj.spec.spawn, traj.spec.episode))
    known = MOVED_BY_A_DOOR if written_type == "Door" else set()
    assert moved == {e for e in known if e in ((t.spec.spawn, t.spec.episode) for t in trajs)}


#: The one committed episode (builtin-7+p3) where a hallucinated Door still moves memory
#: metrics: at steps 3-4 its map holds four entries, and a frame through the sign pairs all
#: five with objects (chairs stand in a grid), so PA, which chooses the frame, prefers it;
#: the spells Chair_9 and Chair_10 begin at step 4 are lost and serial position moves. A
#: known limit of choosing the frame by PA on a map this sparse, held here so it cannot spread.
MOVED_BY_A_DOOR: set[tuple[str, int]] = {("conference", 10)}


# --- 4. over-reporting never pays ---------------------------------------------------------


def _random_map(truth: list[GroundTruthObject], n: int, rng: np.random.Generator) -> list:
    xy = np.array([(o.x, o.z) for o in truth])
    low, high = xy.min(axis=0) - 1.0, xy.max(axis=0) + 1.0
    kinds = [truth[i].object_type for i in rng.integers(0, len(truth), n)]
    return [
        MapEntry(f"guess {i}", k, *rng.uniform(low, high).tolist()) for i, k in enumerate(kinds)
    ]


@pytest.mark.slow
def test_a_thousand_random_guesses_score_no_higher_than_41(committed: list[Trajectory]) -> None:
    # Issue: 1,000 random entries scored AEC 1.000 and PA 0.868, passing every shipped gate.
    for seed, traj in enumerate(committed):
        truth = list(traj.ground_truth.objects)
        g_base = len(traj.ground_truth.discoverable_ids)
        rng = np.random.default_rng(seed)
        many = positional_accuracy_score(match_map(_random_map(truth, 1000, rng), truth), g_base)
        few = positional_accuracy_score(match_map(_random_map(truth, 41, rng), truth), g_base)
        assert many is not None and few is not None
        assert many <= few


@pytest.mark.slow
@pytest.mark.parametrize("sigma", [0.0, 0.2, 0.5, 1.0, 2.0, 3.0])
def test_500_extra_random_entries_raise_no_maps_pa(
    committed: list[Trajectory], sigma: float
) -> None:
    # Issue: 500 random entries added to a noisy map (sigma 2 m) raised its PA 0.66 -> 0.82.
    for seed, traj in enumerate(committed):
        truth = list(traj.ground_truth.objects)
        g_base = len(traj.ground_truth.discoverable_ids)
        rng = np.random.default_rng(seed)
        noisy = [MapEntry(f"{o.object_type} {i}", o.object_type,
                          *(rng.normal((o.x, o.z), sigma) if sigma else (o.x, o.z)))
                 for i, o in enumerate(truth)]  # fmt: skip
        before = positional_accuracy_score(match_map(noisy, truth), g_base)
        after = positional_accuracy_score(
            match_map([*noisy, *_random_map(truth, 500, rng)], truth), g_base
        )
        assert before is not None and after is not None
        assert after <= before
