"""Anchored Kaplan-Meier, EFC and the Ebbinghaus fit: worked example, oracle, properties."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from lifelines import KaplanMeierFitter

from pytest_emrd.errors import ConfigError
from pytest_emrd.metrics import anchored_km, ebbinghaus_fit, efc

spells = st.lists(st.tuples(st.integers(1, 30), st.booleans()), min_size=1, max_size=60)


def test_km_appendix_b_laptops() -> None:
    # 50 laptops, 30 mapped (C = 0.60); 3, 2 and 5 forgotten at tau = 1, 2, 3; 20 retained.
    durations = [1] * 3 + [2] * 2 + [3] * 5 + [3] * 20
    observed = [True] * 10 + [False] * 20
    km = anchored_km(durations, observed, coverage=30 / 50)
    assert km.at_risk == (30, 30, 27, 25)
    assert km.events == (0, 3, 2, 5)
    assert km.survival[1] == pytest.approx(0.54, abs=1e-12)
    assert km.survival[2] == pytest.approx(0.50, abs=1e-12)
    assert km.survival[3] == pytest.approx(0.40, abs=1e-12)
    assert km.at(2.5) == km.survival[2]


@given(spells)
def test_km_agrees_with_lifelines(data: list[tuple[int, bool]]) -> None:
    durations = [d for d, _ in data]
    observed = [e for _, e in data]
    ours = anchored_km(durations, observed, coverage=1.0)
    fitter = KaplanMeierFitter().fit(durations, event_observed=observed)
    theirs = fitter.survival_function_at_times(list(ours.times[1:])).to_numpy()
    assert np.allclose(ours.survival[1:], theirs, atol=1e-12)


@given(spells, st.floats(0.0, 1.0))
def test_anchored_km_starts_at_coverage_and_never_increases(
    data: list[tuple[int, bool]], coverage: float
) -> None:
    km = anchored_km([d for d, _ in data], [e for _, e in data], coverage=coverage)
    assert km.survival[0] == coverage
    assert all(b <= a + 1e-15 for a, b in zip(km.survival, km.survival[1:], strict=False))
    assert all(0.0 <= s <= 1.0 for s in km.survival)


@pytest.mark.parametrize(
    ("durations", "observed", "survival"),
    [([], [], (0.7,)), ([2, 5], [False, False], (0.7, 0.7, 0.7))],
    ids=["no-spells", "no-events-flat"],
)
def test_km_edge_cases(durations: list[int], observed: list[bool], survival: tuple[float]) -> None:
    assert anchored_km(durations, observed, coverage=0.7).survival == survival


def test_km_ties_are_counted_together() -> None:
    km = anchored_km([2, 2, 2, 4], [True, True, False, True], coverage=1.0)
    assert km.events == (0, 2, 1)
    assert km.survival == (1.0, 0.5, 0.0)  # n=4, d=2 at tau=2; n=1, d=1 at tau=4


def test_a_repeated_fit_gives_every_bit_again() -> None:
    # the KM curve, the Ebbinghaus R^2 and its gate fit the same pooled spells
    first = anchored_km([3, 1, 2, 2], [True, False, True, False], coverage=0.5)
    again = anchored_km(np.array([3.0, 1.0, 2.0, 2.0]), np.array([1, 0, 1, 0]), coverage=0.5)
    assert again == first
    zero, negative_zero = (
        anchored_km([3, 1], [True, False], coverage=c).survival[0] for c in (0.0, -0.0)
    )
    assert (math.copysign(1.0, zero), math.copysign(1.0, negative_zero)) == (1.0, -1.0)


@pytest.mark.parametrize(
    ("durations", "observed", "coverage"),
    [([1, 2], [True], 0.5), ([0], [True], 0.5), ([float("nan")], [True], 0.5),
     ([1], [True], 1.5), ([-1], [False], 0.5)],
    ids=["length-mismatch", "zero-duration", "nan-duration", "coverage-above-1",
         "negative-duration"],
)  # fmt: skip
def test_bad_spell_input_is_rejected(
    durations: list[float], observed: list[bool], coverage: float
) -> None:
    with pytest.raises(ConfigError):
        anchored_km(durations, observed, coverage=coverage)


def test_efc_worked_example_and_edges() -> None:
    assert efc([4, 6, 10], [True, False, True]) == 10.0
    assert efc([], []) is None
    assert efc([5, 7], [False, False]) == math.inf


@given(st.integers(0, 2**32 - 1), st.floats(1.0, 50.0))
def test_efc_recovers_the_exponential_mean_on_large_samples(seed: int, mean: float) -> None:
    rng = np.random.default_rng(seed)
    life = rng.exponential(mean, 20_000)
    censor = rng.uniform(0.0, 3.0 * mean, 20_000)
    durations = np.minimum(life, censor)
    observed = life <= censor
    keep = durations > 0
    estimate = efc(durations[keep], observed[keep])
    assert estimate is not None
    assert estimate == pytest.approx(mean, rel=0.05)


def test_ebbinghaus_fits_exponential_survival_well() -> None:
    rng = np.random.default_rng(7)
    durations = np.ceil(rng.exponential(8.0, 5000))
    fit = ebbinghaus_fit(durations, np.ones(5000, dtype=bool), coverage=0.8)
    assert fit.efc == pytest.approx(8.5, rel=0.05)  # discretised: ceil adds ~1/2 step
    assert fit.r2 is not None and fit.r2 > 0.95


def test_ebbinghaus_r2_is_negative_for_abrupt_truncation() -> None:
    durations = [20] * 50 + list(range(1, 20)) * 5
    observed = [True] * 50 + [False] * 95
    fit = ebbinghaus_fit(durations, observed, coverage=0.9)
    assert fit.efc == 39.0
    assert fit.r2 is not None and fit.r2 < 0


@pytest.mark.parametrize(
    ("durations", "observed", "efc_value", "reason_part"),
    [
        ([], [], None, "no spells"),
        ([3, 3], [False, False], math.inf, "unbounded"),
        ([3, 3], [True, True], 3.0, "does not vary"),
    ],
    ids=["no-spells", "no-events", "single-time-point"],
)
def test_ebbinghaus_edge_cases(
    durations: list[int], observed: list[bool], efc_value: float | None, reason_part: str
) -> None:
    # one duration: a single point on the "durations" grid (the other grids add t = 0)
    fit = ebbinghaus_fit(durations, observed, coverage=0.5, points="durations")
    assert fit.efc == efc_value
    assert fit.r2 is None
    assert fit.reason is not None and reason_part in fit.reason


@pytest.mark.parametrize(
    ("points", "r2"),
    [("steps", -0.5685), ("events", 0.2829), ("durations", -0.5724)],
)
def test_r2_of_a_hard_window_on_each_grid_of_evaluation_points(points: str, r2: float) -> None:
    # a plateau then a cliff at 20: two event-time points fit an exponential fairly well
    durations = [20] * 50 + list(range(1, 20)) * 5
    observed = [True] * 50 + [False] * 95
    fit = ebbinghaus_fit(durations, observed, coverage=0.9, points=points)
    assert fit.points == points
    assert fit.r2 == pytest.approx(r2, abs=1e-4)


def test_unknown_r2_points_is_a_clear_error() -> None:
    with pytest.raises(ConfigError, match="points='knots' is not one of"):
        ebbinghaus_fit([1, 2], [True, False], coverage=0.5, points="knots")


@given(spells, st.floats(0.0, 1.0))
def test_greenwood_band_holds_the_curve_and_matches_lifelines(
    data: list[tuple[int, bool]], coverage: float
) -> None:
    durations, observed = [d for d, _ in data], [e for _, e in data]
    km = anchored_km(durations, observed, coverage=coverage)
    assert all(lo - 1e-12 <= s <= hi + 1e-12
               for lo, s, hi in zip(km.ci_low, km.survival, km.ci_high, strict=True))  # fmt: skip
    band = KaplanMeierFitter().fit(durations, observed).confidence_interval_.to_numpy()
    finite = np.isfinite(band[:, 0])
    assert np.allclose(np.asarray(km.ci_low)[finite], coverage * band[finite, 0], atol=1e-12)
