"""The estimators behind the mimic rows: RMSE read back from PA, pooled sigma, rate rows."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from pytest_emrd.metrics import MatchedPair, Matching, positional_accuracy_score, rigid_fit
from pytest_emrd.validate._mimic import rate_check, rmse_from_pa, sigma_estimate


def _pa(truth: np.ndarray, pred: np.ndarray, g_base: int) -> float | None:
    pairs = tuple(
        MatchedPair(f"chair {i}", f"Chair_{i}", "Chair", px, pz, tx, tz)
        for i, ((px, pz), (tx, tz)) in enumerate(zip(pred.tolist(), truth.tolist(), strict=True))
    )
    return positional_accuracy_score(Matching(pairs, (), (), (), len(pairs)), g_base)


def _moved(points: np.ndarray, theta: float, shift: tuple[float, float]) -> np.ndarray:
    rot = np.array([[math.cos(theta), -math.sin(theta)], [math.sin(theta), math.cos(theta)]])
    return points @ rot.T + np.array(shift)


@given(
    seed=st.integers(0, 2**32 - 1),
    n=st.integers(3, 40),
    noise=st.floats(0.01, 1.0),
    theta=st.floats(-math.pi, math.pi),
    shift=st.tuples(st.floats(-50, 50), st.floats(-50, 50)),
    extra=st.integers(0, 10),
)
def test_rmse_read_back_from_pa_is_the_procrustes_residual(seed, n, noise, theta, shift, extra):
    rng = np.random.default_rng(seed)
    truth = rng.uniform(-6, 6, size=(n, 2))
    pred = _moved(truth + rng.normal(0, noise, size=(n, 2)), theta, shift)
    rot, t = rigid_fit(pred, truth)
    direct = math.sqrt(np.mean(np.sum((pred @ rot.T + t - truth) ** 2, axis=1)))
    read = rmse_from_pa(_pa(truth, pred, n + extra), n, n + extra, truth)
    assert read == pytest.approx(direct, rel=1e-6, abs=1e-9)


def test_sigma_is_recovered_from_pa_of_noisy_maps() -> None:
    # Worked example: 300 maps of 20 objects, sigma = 0.25 m per coordinate, each map in its
    # own frame; no placement error of its own (SSR_0 = 0).
    rng = np.random.default_rng(7)
    rows = []
    for _ in range(300):
        truth = rng.uniform(-5, 5, size=(20, 2))
        pred = _moved(truth + rng.normal(0, 0.25, size=truth.shape), rng.uniform(0, 6), (3, -4))
        rmse = rmse_from_pa(_pa(truth, pred, 20), 20, 20, truth)
        rows.append((20 * rmse**2, 2 * 20 - 3))
    assert sigma_estimate(np.array(rows)) == pytest.approx(0.25, rel=0.03)


@pytest.mark.parametrize(
    ("rows", "expected"),
    [
        pytest.param([], math.nan, id="no-rows"),
        pytest.param([(-1.0, 37.0)], 0.0, id="negative-excess"),
        pytest.param([(0.37, 37.0), (0.0, 0.0)], 0.1, id="pooled"),
    ],
)
def test_sigma_estimate_edge_cases(rows, expected) -> None:
    got = sigma_estimate(np.array(rows))
    assert (math.isnan(got) and math.isnan(expected)) or got == pytest.approx(expected)


@pytest.mark.parametrize(
    ("pa", "matched", "g_base", "points"),
    [
        pytest.param(None, 3, 3, [(0, 0), (1, 0), (0, 1)], id="pa-undefined"),
        pytest.param(0.0, 3, 3, [(0, 0), (1, 0), (0, 1)], id="pa-zero"),
        pytest.param(0.5, 1, 3, [(0, 0)], id="one-point"),
        pytest.param(0.5, 3, 0, [(0, 0), (1, 0), (0, 1)], id="no-g-base"),
    ],
)
def test_rmse_cannot_be_read_back(pa, matched, g_base, points) -> None:
    assert math.isnan(rmse_from_pa(pa, matched, g_base, np.array(points, dtype=float)))


@pytest.mark.parametrize(
    ("planted", "count", "verdict"),
    [(0.04, 4, "pass"), (0.2, 4, "fail"), (0.0, 0, "pass"), (0.0, 1, "fail")],
)
def test_rate_rows_use_the_clopper_pearson_interval(planted, count, verdict) -> None:
    row = rate_check("Replies", "Parse failures, mimic", planted, count, 100, "over all steps")
    assert row.verdict == verdict
    assert row.data["ci_low"] <= count / 100 <= row.data["ci_high"]
