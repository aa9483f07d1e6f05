"""Statistics of the paper: bootstrap CIs, Pearson chi-square, Fisher exact, Cramer's V, ANOVA.

scipy and statsmodels are the engines (imported on first use, so importing the metrics
package stays cheap for the plugin); this module fixes the conventions (no continuity
correction, two-sided tests, seeded percentile bootstrap) and turns degenerate input into a
result with a reason instead of a warning or a NaN.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from pytest_emrd.errors import ConfigError

#: Bootstrap resamples behind every confidence interval.
N_RESAMPLES = 2000


@dataclass(frozen=True)
class Estimate:
    """A gate metric's value with its bootstrap 95 % confidence interval."""

    value: float | None
    """The estimate; None when undefined (see ``reason``), ``inf`` when unbounded."""
    ci_low: float | None
    """Lower end of the percentile bootstrap 95 % CI; None when ``n < 2`` or undefined."""
    ci_high: float | None
    n: int
    """Episodes contributing to the value."""
    reason: str | None = None
    """Why ``value`` (or the CI) is missing or unbounded; None when all is defined."""
    excluded: int = 0
    """Episodes left out: errored, or where the metric is undefined (e.g. SIR, no re-entry)."""


@functools.lru_cache(maxsize=4)
def resample_rows(rng_seed: int, n: int, n_resamples: int) -> np.ndarray:
    """The bootstrap's ``(n_resamples, n)`` row indices drawn from
    ``numpy.random.default_rng(rng_seed)``: a function of its arguments alone, so computed once
    and shared (read-only) by every interval over ``n`` episodes with that seed (the gate
    metrics of one run)."""
    idx = np.random.default_rng(rng_seed).integers(0, n, size=(n_resamples, n))
    idx.flags.writeable = False
    return idx


def bootstrap_ci(
    data: Sequence[float] | np.ndarray,
    statistic: Callable[[np.ndarray], np.ndarray] | None = None,
    *,
    rng_seed: int = 0,
    n_resamples: int = N_RESAMPLES,
    confidence: float = 0.95,
) -> tuple[float | None, float | None]:
    r"""Seeded percentile bootstrap CI of ``statistic`` over the rows of ``data``.

    Resamples rows with replacement ``n_resamples`` times from
    ``numpy.random.default_rng(rng_seed)`` and returns the ``(1 - confidence) / 2`` and
    ``(1 + confidence) / 2`` quantiles of the resampled statistic (percentile method, as
    :func:`scipy.stats.bootstrap` with ``method="percentile"`` computes it; done here with one
    index matrix so a pooled ratio can be bootstrapped by episode). ``statistic`` receives an
    array of shape ``(n_resamples, n, ...)`` and returns ``n_resamples`` values; the default is
    the mean over axis 1. Edge cases: ``n < 2`` gives ``(None, None)``; identical values give
    a zero-width interval; resamples whose statistic is NaN are dropped, and all NaN gives
    ``(None, None)``; ``inf`` is kept (an unbounded end stays unbounded).
    """
    arr = np.asarray(data, dtype=float)
    if len(arr) < 2:
        return None, None
    idx = resample_rows(rng_seed, len(arr), n_resamples)
    fn = statistic if statistic is not None else (lambda a: a.mean(axis=1))
    with np.errstate(divide="ignore", invalid="ignore"):
        values = np.asarray(fn(arr[idx]), dtype=float)
    return _percentiles(values, confidence)


def draw_counts(idx: np.ndarray) -> np.ndarray:
    """How often each of ``n`` rows appears in each row of ``idx`` (``n_resamples x n`` row
    indices): the ``n_resamples x n`` counts as read-only floats, ready to multiply data."""
    n_resamples, n = idx.shape
    flat = (idx + n * np.arange(n_resamples)[:, None]).ravel()  # row r counts into r*n ..
    counts = np.bincount(flat, minlength=n_resamples * n).reshape(n_resamples, n)
    counts = counts.astype(float)
    counts.flags.writeable = False
    return counts


def bootstrap_sums_ci(
    data: np.ndarray,
    statistic: Callable[[np.ndarray], np.ndarray],
    *,
    rng_seed: int = 0,
    n_resamples: int = N_RESAMPLES,
    confidence: float = 0.95,
) -> tuple[float | None, float | None]:
    r""":func:`bootstrap_ci` of a statistic of the resampled column sums of whole-number
    ``data`` (n x k counts: events, steps, one-hot choices).

    ``statistic`` receives the ``(n_resamples, k)`` sums ``data[rows].sum(axis=1)`` of the
    resamples of :func:`bootstrap_ci` and returns ``n_resamples`` values. The sums are taken
    as resample counts (:func:`draw_counts`) times ``data``: for whole numbers below ``2**53``
    every partial sum is exact, so this is the row resampling's interval, bit for bit, without
    gathering ``n_resamples x n`` rows. Edge cases as :func:`bootstrap_ci`.
    """
    arr = np.asarray(data, dtype=float)
    if len(arr) < 2:
        return None, None
    sums = draw_counts(resample_rows(rng_seed, len(arr), n_resamples)) @ arr
    with np.errstate(divide="ignore", invalid="ignore"):
        values = np.asarray(statistic(sums), dtype=float)
    return _percentiles(values, confidence)


def _percentiles(values: np.ndarray, confidence: float) -> tuple[float | None, float | None]:
    """The percentile interval of the resampled statistic (NaN resamples dropped)."""
    values = values[~np.isnan(values)]
    if not len(values):
        return None, None
    alpha = (1.0 - confidence) / 2.0
    with np.errstate(invalid="ignore"):  # inf - inf while interpolating between inf values
        low, high = np.quantile(values, [alpha, 1.0 - alpha], method="linear")
    return float(low) if not np.isnan(low) else math.inf, (
        float(high) if not np.isnan(high) else math.inf
    )


@dataclass(frozen=True)
class ChiSquare:
    """Pearson chi-square test of independence on a k x c table."""

    statistic: float | None
    dof: int
    p_value: float | None
    n: int
    """Total count."""
    dropped: tuple[str, ...]
    """Rows/columns removed because they were all zero (``row 2``, ``column 0``)."""
    reason: str | None = None


def _table(table: Sequence[Sequence[float]] | np.ndarray, name: str) -> np.ndarray:
    arr = np.asarray(table, dtype=float)
    if arr.ndim != 2 or arr.size == 0:
        raise ConfigError(f"{name} shape={arr.shape} must be a non-empty 2-D table of counts.")
    if not np.all(np.isfinite(arr)) or np.any(arr < 0):
        raise ConfigError(f"{name} must hold finite counts >= 0; got {arr.tolist()}.")
    return arr


def chi_square(table: Sequence[Sequence[float]] | np.ndarray) -> ChiSquare:
    r"""Pearson chi-square test of independence (no continuity correction).

    .. math::
        \chi^2 = \sum_{i,j} \frac{(O_{ij} - E_{ij})^2}{E_{ij}},\quad
        E_{ij} = \frac{R_i C_j}{N},\quad df = (k-1)(c-1)

    Rows are groups (conditions, spawn rooms), columns outcomes. All-zero rows and columns
    carry no information and make ``E_ij = 0``; they are dropped and listed. If fewer than two
    rows or columns remain the statistic is None with a reason. Engine:
    :func:`scipy.stats.chi2_contingency` with ``correction=False`` (the paper's Pearson test).
    """
    arr = _table(table, "table")
    rows = arr.sum(axis=1) > 0
    cols = arr.sum(axis=0) > 0
    dropped = tuple(f"row {i}" for i in np.flatnonzero(~rows)) + tuple(
        f"column {j}" for j in np.flatnonzero(~cols)
    )
    kept = arr[rows][:, cols]
    n = round(float(arr.sum()))
    if kept.shape[0] < 2 or kept.shape[1] < 2:
        why = "fewer than two non-empty rows or columns: independence is untestable"
        return ChiSquare(None, 0, None, n, dropped, why)
    from scipy.stats import chi2_contingency  # heavy: imported on first use

    res = chi2_contingency(kept, correction=False)
    return ChiSquare(float(res.statistic), int(res.dof), float(res.pvalue), n, dropped)


@dataclass(frozen=True)
class FisherExact:
    """Two-sided Fisher exact test on a 2 x 2 table."""

    odds_ratio: float
    """Sample odds ratio ``(a d) / (b c)`` (``inf`` or ``nan`` with zero cells, as scipy)."""
    p_value: float


def fisher_exact_2x2(table: Sequence[Sequence[float]] | np.ndarray) -> FisherExact:
    """Two-sided Fisher exact test (:func:`scipy.stats.fisher_exact`) of a 2 x 2 count table.

    Rows are the reference and the compared group, columns the binary outcome (e.g. chose the
    Conference Room vs any other room). An all-zero row or column gives ``p = 1``.
    """
    arr = _table(table, "table")
    if arr.shape != (2, 2):
        raise ConfigError(f"table shape={arr.shape} must be 2 x 2 for Fisher's exact test.")
    if np.any(arr != np.round(arr)):
        raise ConfigError(f"table={arr.tolist()} must hold whole counts for Fisher's exact test.")
    from scipy.stats import fisher_exact  # heavy: imported on first use

    res = fisher_exact(arr.astype(np.int64), alternative="two-sided")
    return FisherExact(float(res.statistic), float(res.pvalue))


def cramers_v(table: Sequence[Sequence[float]] | np.ndarray) -> float | None:
    r"""Cramer's V effect size of a k x c table (no bias correction).

    .. math::
        V = \sqrt{\frac{\chi^2}{N\,(\min(k, c) - 1)}}

    In [0, 1], from :func:`chi_square` (so all-zero rows and columns are dropped first and
    ``min(k, c)`` counts what is left); agrees with
    :func:`scipy.stats.contingency.association` (``method="cramer"``). An untestable table
    (fewer than two non-empty rows or columns) gives None.
    """
    res = chi_square(table)
    if res.statistic is None:
        return None
    arr = _table(table, "table")
    shape = (int(np.sum(arr.sum(axis=1) > 0)), int(np.sum(arr.sum(axis=0) > 0)))
    return math.sqrt(res.statistic / (float(arr.sum()) * (min(shape) - 1)))


@dataclass(frozen=True)
class Anova:
    """One-way ANOVA of per-episode memory strength across conditions."""

    statistic: float | None
    """F statistic."""
    p_value: float | None
    df_between: float
    df_within: float
    groups: dict[str, int]
    """Condition -> episodes used."""
    reason: str | None = None


def anova_groups(groups: Mapping[str, Sequence[float]]) -> Anova:
    r"""Classic one-way ANOVA (equal variances) of ``groups`` (statsmodels ``anova_oneway``).

    .. math::
        F = \frac{\sum_g n_g (\bar{y}_g - \bar{y})^2 / (G - 1)}
                 {\sum_g \sum_i (y_{gi} - \bar{y}_g)^2 / (N - G)}

    Non-finite values are dropped; groups left empty are dropped. Fewer than two groups, or no
    within-group variation (every group has a single value), gives None with a reason; all
    values identical gives ``F = 0``-style degeneracy reported as None with a reason.
    """
    clean = {
        name: np.asarray([v for v in values if math.isfinite(v)], dtype=float)
        for name, values in groups.items()
    }
    clean = {name: v for name, v in clean.items() if len(v)}
    sizes = {name: len(v) for name, v in clean.items()}
    n = sum(sizes.values())
    if len(clean) < 2:
        return Anova(None, None, 0.0, 0.0, sizes, "fewer than two conditions with finite values")
    if n - len(clean) < 1:
        return Anova(None, None, len(clean) - 1.0, 0.0, sizes, "no within-condition variation")
    pooled = np.concatenate(list(clean.values()))
    within = sum(float(np.sum((v - v.mean()) ** 2)) for v in clean.values())
    if within == 0.0:
        why = "every condition is constant: F is undefined"
        if np.ptp(pooled) == 0.0:
            why = "all values are identical: F is undefined"
        return Anova(None, None, len(clean) - 1.0, n - len(clean) + 0.0, sizes, why)
    from statsmodels.stats.oneway import anova_oneway  # heavy: imported on first use

    res = anova_oneway(list(clean.values()), use_var="equal")
    return Anova(float(res.statistic), float(res.pvalue), float(res.df_num), float(res.df_denom),
                 sizes)  # fmt: skip
