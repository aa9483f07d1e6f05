"""Remember rows on hand-built and synthetic trajectories: pass when the truth is recovered,
fail when it is not."""

from __future__ import annotations

import math

import pytest

from pytest_emrd.metrics.synthetic import synthetic_grid
from pytest_emrd.rooms import ROOM_NAMES
from pytest_emrd.validate import (
    decay_checks,
    episodes_needed,
    error_curve,
    miller_checks,
    monotone,
    serial_checks,
    u_depth,
    window_fit_checks,
)

OFFICE = ROOM_NAMES[0]


@pytest.fixture(scope="module")
def decay8() -> list:
    return synthetic_grid(conditions=("baseline",), episodes=5, mean_memory=8.0)


def test_decay_rows_pass_on_the_planted_mean(decay8: list) -> None:
    efc, r2 = decay_checks({8.0: decay8})
    assert (efc.verdict, r2.verdict) == ("pass", "pass")
    assert efc.data["error"] <= 0.25 and efc.data["episodes_needed"] is not None
    assert "20 episodes" in efc.note


def test_decay_row_fails_on_a_wrong_planted_mean(decay8: list) -> None:
    efc, _ = decay_checks({20.0: decay8})
    assert efc.verdict == "fail"
    assert efc.data["episodes_needed"] is None


def test_error_curve_uses_spawn_balanced_prefixes(decay8: list) -> None:
    curve = error_curve(decay8, 8.0)
    assert [n for n, _ in curve] == [4, 8, 12, 16, 20]
    assert all(e >= 0 for _, e in curve)


@pytest.mark.parametrize(
    ("curve", "needed"),
    [
        pytest.param([(4, 0.1), (8, 0.2)], 4, id="always-within"),
        pytest.param([(4, 0.5), (8, 0.1), (12, 0.2)], 8, id="within-from-8"),
        pytest.param([(4, 0.1), (8, 0.3), (12, 0.2)], 12, id="leaves-then-returns"),
        pytest.param([(4, 0.1), (8, math.inf)], None, id="never-at-the-end"),
        pytest.param([], None, id="no-prefix"),
    ],
)
def test_episodes_needed(curve: list, needed: int | None) -> None:
    assert episodes_needed(curve, 0.25) == needed


@pytest.mark.parametrize("k", [10, 15])
def test_miller_inflection_recovers_a_hand_built_window(build, window, k: int) -> None:
    trajs = [build(window(k), episode=e) for e in range(2)]
    (row, perfect) = miller_checks({k: trajs}, [build(window(100))])
    assert row.verdict == "pass", row.note
    assert row.data["m_star"] == k
    assert perfect.verdict == "pass" and perfect.data["max_probability"] == 0.0


def test_miller_row_recovers_a_capacity_inside_the_first_bin(build, window) -> None:
    # Loads never exceed k = 5 = w, so every step falls in bin 1: the rise is the one from
    # the anchor ML(0) = 0 into bin 1.
    (row, _) = miller_checks({5: [build(window(5))]}, [build(window(100))])
    assert row.verdict == "pass", row.note
    assert (row.data["b_star"], row.data["m_star"]) == (1, 5)


def test_miller_row_fails_when_the_capacity_is_elsewhere(build, window) -> None:
    (row, perfect) = miller_checks({20: [build(window(10))]}, [build(window(5))])
    assert row.verdict == "fail" and row.data["m_star"] == 10
    assert perfect.verdict == "fail" and perfect.data["max_probability"] > 0


def test_window_fits_worse_than_decay_at_matched_mean(build, window, decay8) -> None:
    # window(8): every object is held exactly 8 steps out of view, then dropped.
    (row,) = window_fit_checks({8: [build(window(9), episode=e) for e in range(4)]},
                               {8.0: decay8})  # fmt: skip
    assert row.verdict == "pass", row.note
    assert row.data["r2_window"] < row.data["r2_decay"] - 0.1


def test_window_fit_row_fails_without_forgetting(build, window, decay8) -> None:
    (row,) = window_fit_checks({8: [build(window(100))]}, {8.0: decay8})
    assert row.verdict == "fail" and "no finite EFC" in row.note


def _serial_frames(chairs, drop_middle: bool) -> list:
    """Nine objects found one per step; the middle three are dropped one step out of view."""
    frames = []
    for t in range(1, 31):
        visible = chairs(t) if t <= 9 else []
        held = [c for c in chairs(*range(1, min(t, 9) + 1))]
        if drop_middle:
            held = [c for c in held if c not in chairs(4, 5, 6) or c in visible]
        frames.append((OFFICE, visible, held))
    return frames


def test_serial_u_shape_passes_and_window_is_monotone(build, window, chairs) -> None:
    serial = [build(_serial_frames(chairs, True))]
    u_row, w_row = serial_checks(serial, {5: [build(window(5))]})
    assert u_row.verdict == "pass", u_row.recovered
    assert (u_row.data["early"], u_row.data["middle"], u_row.data["late"]) == (
        math.inf, 1.0, math.inf,
    )  # fmt: skip
    assert "the paper's Eq. SPE" in u_row.note and u_row.data["paper_middle"] == 1.0
    assert w_row.verdict == "pass", w_row.recovered
    assert w_row.data["u_depth"] == 0.0 and "monotone within 10%: yes" in w_row.note
    # Each object goes 5 steps after leaving view, except the last five: nothing new pushes
    # them out, so they are censored at the end (5 events, 60 steps in the Late third).
    assert (w_row.data["early"], w_row.data["middle"], w_row.data["late"]) == (5.0, 5.0, 12.0)


def test_serial_row_fails_without_a_dip(build, chairs) -> None:
    (u_row,) = serial_checks([build(_serial_frames(chairs, False))], {})
    assert u_row.verdict == "fail"


def test_paper_estimator_under_perfect_memory_is_a_finding(build, chairs) -> None:
    """Nothing forgotten: MLE inf everywhere, but the censored TTF falls E > M > L."""
    perfect = [build(_serial_frames(chairs, False))]
    *_, bias = serial_checks(perfect, {}, perfect)
    assert bias.verdict == "finding", bias.recovered
    assert bias.data["paper_early"] > bias.data["paper_middle"] > bias.data["paper_late"]


def test_perfect_memory_row_fails_when_something_is_forgotten(build, chairs) -> None:
    forgetful = [build(_serial_frames(chairs, True))]
    *_, bias = serial_checks(forgetful, {}, forgetful)
    assert bias.verdict == "fail"


INF = math.inf


@pytest.mark.parametrize(
    ("profile", "ok"),
    [
        pytest.param((1.0, 2.0, 3.0), True, id="rising"),
        pytest.param((3.0, 2.0, 1.0), True, id="falling"),
        pytest.param((2.0, 2.0, 2.0), True, id="flat"),
        pytest.param((2.0, 2.15, 2.0), True, id="bump-within-10pct"),
        pytest.param((2.0, 1.85, 2.0), True, id="dip-within-10pct"),
        pytest.param((2.0, 2.3, 2.0), False, id="inverted-U"),
        pytest.param((3.0, 1.0, 3.0), False, id="U"),
        pytest.param((INF, 3.0, INF), False, id="U-protected-ends"),
        pytest.param((INF, INF, INF), True, id="never-forgets"),
        pytest.param((2.0, 3.0, INF), True, id="rising-to-inf"),
        pytest.param((None, 1.0, 1.0), False, id="undefined-third"),
    ],
)
def test_monotone_definition(profile: tuple, ok: bool) -> None:
    assert monotone(*profile) is ok


def test_window_row_fails_on_a_planted_u(build, chairs) -> None:
    _, w_row = serial_checks([], {5: [build(_serial_frames(chairs, True))]})
    assert w_row.verdict == "fail" and w_row.data["u_depth"] == 1.0
    assert "monotone within 10%: no" in w_row.note


@pytest.mark.parametrize(
    ("profile", "depth"),
    [
        pytest.param((1.0, 2.0, 3.0), 0.0, id="rising"),
        pytest.param((2.0, 3.0, 2.0), 0.0, id="inverted-U"),
        pytest.param((4.0, 3.0, 6.0), 0.25, id="dip-below-the-nearer-end"),
        pytest.param((INF, 3.0, INF), 1.0, id="protected-ends"),
        pytest.param((INF, INF, INF), 0.0, id="never-forgets"),
        pytest.param((INF, 1.0, 4.0), 0.75, id="one-end-protected"),
        pytest.param((1.0, None, 1.0), None, id="undefined-third"),
    ],
)
def test_u_depth(profile: tuple, depth: float | None) -> None:
    assert u_depth(*profile) == depth
