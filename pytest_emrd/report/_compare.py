"""``emrd report --compare RUN_A RUN_B``: what a release changed, per metric and cell (pure).

For every model x variant x condition present in both runs and every compared gate metric:
the value in each run (``GATE_METRICS[name].compute``), the difference ``B - A``, and a seeded
two-sample percentile bootstrap 95 % CI of the difference (:func:`scipy.stats.bootstrap`,
episodes of A and B resampled independently). A difference is significant when its CI
excludes 0.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any, Final

import numpy as np
from scipy import stats

from pytest_emrd._serde import from_dict, to_dict
from pytest_emrd.metrics import GATE_METRICS, EpisodeMetrics, Estimate, as_episode_metrics
from pytest_emrd.metrics._stats import N_RESAMPLES
from pytest_emrd.report._build import group_cells
from pytest_emrd.trajectory import Trajectory

Value = Callable[[EpisodeMetrics], float | bool | None]

#: Metrics averaged over episodes: name -> per-episode value (None: undefined, left out).
_MEANS: Final[dict[str, Value]] = {
    "aec": lambda m: m.aec,
    "te": lambda m: m.te,
    "pa": lambda m: m.pa,
    "fpsg_local": lambda m: m.fpsg_local,
    "fpsg_global": lambda m: m.fpsg_global,
    "never_visited": lambda m: m.never_visited,
    "any_bias": lambda m: m.any_bias,
    "sir": lambda m: m.sir,
}
#: Pooled ratios: name -> (numerator, denominator) per episode.
_RATIOS: Final[dict[str, tuple[Callable[[EpisodeMetrics], float], ...]]] = {
    "memory_strength": (lambda m: m.retained_steps, lambda m: m.forget_events),
    "parse_failure_rate": (lambda m: m.parse_failures, lambda m: m.steps),
}
#: Compared metrics, in report order (every one a key of GATE_METRICS).
COMPARED: Final[tuple[str, ...]] = (*_MEANS, *_RATIOS, "errored_rate")


@dataclass(frozen=True)
class Difference:
    """One metric of one cell in run A and run B."""

    model: str
    variant: str
    condition: str
    metric: str
    a: Estimate
    b: Estimate
    diff: float | None
    """``b.value - a.value``; None when either is undefined or unbounded."""
    ci_low: float | None
    ci_high: float | None
    significant: bool | None
    """The CI excludes 0; None without a CI."""
    reason: str | None = None
    """Why ``diff`` or its CI is missing."""


@dataclass(frozen=True)
class Comparison:
    run_a: str
    run_b: str
    differences: tuple[Difference, ...]
    only_a: tuple[str, ...]
    """Cells (``model/variant/condition``) only run A holds: not compared."""
    only_b: tuple[str, ...]
    rng_seed: int = 0
    n_resamples: int = N_RESAMPLES

    def to_dict(self) -> dict[str, Any]:
        return to_dict(self)

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> Comparison:
        return from_dict(cls, data)


def _samples(name: str, ems: Sequence[EpisodeMetrics]) -> np.ndarray:
    """Bootstrap rows of one run's cell: per-episode values, or ``(2, n)`` num/den rows."""
    kept = [m for m in ems if not m.errored]
    if name in _MEANS:
        return np.array([float(v) for m in kept if (v := _MEANS[name](m)) is not None])
    if name in _RATIOS:
        num, den = _RATIOS[name]
        return np.array([[num(m) for m in kept], [den(m) for m in kept]], dtype=float)
    return np.array([float(m.errored) for m in ems])


def _statistic(name: str) -> Callable[..., np.ndarray]:
    if name in _RATIOS:

        def ratio(x: np.ndarray) -> np.ndarray:
            # scipy resamples the last axis: (2, n) -> (2, n_resamples, n); row 0 is num
            with np.errstate(divide="ignore", invalid="ignore"):
                return x[0].sum(axis=-1) / x[1].sum(axis=-1)

        return lambda a, b, axis=-1: ratio(b) - ratio(a)
    return lambda a, b, axis=-1: np.mean(b, axis=axis) - np.mean(a, axis=axis)


def _difference(
    key: tuple[str, str, str], name: str, a: Sequence[EpisodeMetrics],
    b: Sequence[EpisodeMetrics], rng_seed: int,
) -> Difference:  # fmt: skip
    ea = GATE_METRICS[name].compute(a, rng_seed=rng_seed)
    eb = GATE_METRICS[name].compute(b, rng_seed=rng_seed)

    def result(diff: float | None, low: float | None = None, high: float | None = None,
               why: str | None = None) -> Difference:  # fmt: skip
        significant = None if low is None or high is None else bool(low > 0 or high < 0)
        return Difference(*key, name, ea, eb, diff, low, high, significant, why)

    if ea.value is None or eb.value is None:
        return result(None, why=f"undefined in run {'A' if ea.value is None else 'B'}: "
                      f"{(ea if ea.value is None else eb).reason}")  # fmt: skip
    if math.isinf(ea.value) or math.isinf(eb.value):
        return result(None, why="unbounded in one run (no forgetting event)")
    diff = eb.value - ea.value
    sa, sb = _samples(name, a), _samples(name, b)
    if sa.shape[-1] < 2 or sb.shape[-1] < 2:
        return result(diff, why="fewer than two episodes in a run: no confidence interval")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        res = stats.bootstrap((sa, sb), _statistic(name), n_resamples=N_RESAMPLES,
                              vectorized=True, axis=-1, method="percentile",
                              rng=np.random.default_rng(rng_seed))  # fmt: skip
    low, high = float(res.confidence_interval.low), float(res.confidence_interval.high)
    if not (math.isfinite(low) and math.isfinite(high)):
        return result(diff, why="the bootstrap distribution is unbounded (resamples without "
                      "any event): no confidence interval")  # fmt: skip
    return result(diff, low, high)


def compare_runs(
    run_a: Sequence[Trajectory],
    run_b: Sequence[Trajectory],
    *,
    names: tuple[str, str] = ("A", "B"),
    rng_seed: int = 0,
) -> Comparison:
    """Every compared metric of every cell the two runs share (see the module docstring)."""
    cells_a = group_cells(as_episode_metrics(run_a))
    cells_b = group_cells(as_episode_metrics(run_b))
    shared = [k for k in cells_a if k in cells_b]
    diffs = tuple(
        _difference(k, name, cells_a[k], cells_b[k], rng_seed) for k in shared for name in COMPARED
    )
    return Comparison(
        names[0], names[1], diffs,
        tuple("/".join(k) for k in cells_a if k not in cells_b),
        tuple("/".join(k) for k in cells_b if k not in cells_a),
        rng_seed,
    )  # fmt: skip
