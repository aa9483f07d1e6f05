"""Statistics of the paper: bootstrap CIs, chi-square, Fisher, Cramer's V, ANOVA, survival.

scipy, statsmodels and lifelines are the engines (imported on first use); this module fixes
the conventions (no continuity correction, two-sided tests, seeded percentile bootstrap) and
turns degenerate input into a result with a reason instead of a warning or a NaN. Survival
inputs are durations (steps retained out of view) with event flags (True: dropped; False:
right-censored); censoring is assumed non-informative, as Kaplan-Meier and the MLE require.
"""

from __future__ import annotations

import bisect
import functools
import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Final

import numpy as np
from numpy.typing import ArrayLike

from pytest_emrd.errors import ConfigError, check_choice, check_range

#: Bootstrap resamples behind every confidence interval, and its level.
N_RESAMPLES = 2000
CONFIDENCE = 0.95


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
    """The bootstrap's ``(n_resamples, n)`` row indices from ``default_rng(rng_seed)``, shared
    read-only by every interval over ``n`` episodes with that seed (the gates of one run)."""
    idx = np.random.default_rng(rng_seed).integers(0, n, size=(n_resamples, n))
    idx.flags.writeable = False
    return idx


def bootstrap_ci(
    data: ArrayLike,
    statistic: Callable[[np.ndarray], np.ndarray] | None = None,
    *,
    rng_seed: int = 0,
    n_resamples: int = N_RESAMPLES,
) -> tuple[float | None, float | None]:
    r"""Seeded percentile bootstrap 95 % CI of ``statistic`` over the rows of ``data``.

    Resamples rows with replacement ``n_resamples`` times from
    ``numpy.random.default_rng(rng_seed)`` and returns the 2.5 % and 97.5 % quantiles
    (:data:`CONFIDENCE`) of the resampled statistic (the percentile method of
    :func:`scipy.stats.bootstrap`, done here with one index matrix so a pooled ratio can be
    bootstrapped by episode). ``statistic`` receives an array of shape
    ``(n_resamples, n, ...)`` and returns ``n_resamples`` values; the default is the mean over
    axis 1. Edge cases: ``n < 2`` gives ``(None, None)``; identical values give a zero-width
    interval; resamples whose statistic is NaN are dropped, and all NaN gives
    ``(None, None)``; ``inf`` is kept (an unbounded end stays unbounded).

    :param data: The sample, one row per unit resampled (an episode).
    :param statistic: Resamples -> one value each; None for the mean over axis 1.
    :param rng_seed: Seed of the resampling generator.
    :param n_resamples: Number of bootstrap resamples.
    :returns: ``(low, high)``, the 95 % percentile interval, or ``(None, None)``.
    """
    arr = np.asarray(data, dtype=float)
    if len(arr) < 2:
        return None, None
    fn = statistic or (lambda a: a.mean(axis=1))
    idx = resample_rows(rng_seed, len(arr), n_resamples)
    with np.errstate(divide="ignore", invalid="ignore"):  # also inf - inf between inf values
        values = np.asarray(fn(arr[idx]), dtype=float)
        values = values[~np.isnan(values)]
        if not len(values):
            return None, None
        alpha = (1.0 - CONFIDENCE) / 2.0
        ends = np.quantile(values, [alpha, 1.0 - alpha])
    low, high = np.where(np.isnan(ends), math.inf, ends).tolist()
    return low, high


def draw_counts(idx: np.ndarray) -> np.ndarray:
    """How often each of ``n`` rows appears in each row of ``idx`` (``n_resamples x n`` row
    indices): the ``n_resamples x n`` counts as read-only floats, ready to multiply data."""
    n_resamples, n = idx.shape
    flat = (idx + n * np.arange(n_resamples)[:, None]).ravel()  # row r counts into r*n ..
    counts = np.bincount(flat, minlength=n_resamples * n).reshape(n_resamples, n).astype(float)
    counts.flags.writeable = False
    return counts


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


def _table(table: ArrayLike, name: str) -> np.ndarray:
    arr = np.asarray(table, dtype=float)
    if arr.ndim != 2 or arr.size == 0:
        raise ConfigError(f"{name} shape={arr.shape} must be a non-empty 2-D table of counts.")
    if not np.all(np.isfinite(arr)) or np.any(arr < 0):
        raise ConfigError(f"{name} must hold finite counts >= 0; got {arr.tolist()}.")
    return arr


def chi_square(table: ArrayLike) -> ChiSquare:
    r"""Pearson chi-square test of independence (no continuity correction).

    .. math::
        \chi^2 = \sum_{i,j} \frac{(O_{ij} - E_{ij})^2}{E_{ij}},\quad
        E_{ij} = \frac{R_i C_j}{N},\quad df = (k-1)(c-1)

    Rows are groups (conditions, spawn rooms), columns outcomes. All-zero rows and columns
    carry no information and make ``E_ij = 0``; they are dropped and listed. If fewer than two
    rows or columns remain the statistic is None with a reason. Engine:
    :func:`scipy.stats.chi2_contingency` with ``correction=False`` (the paper's Pearson test).

    :param table: A k x c table of counts, rows groups, columns outcomes.
    :returns: A :class:`ChiSquare`: statistic, dof, p-value, dropped rows and columns, reason.
    """
    arr = _table(table, "table")
    kept, dropped = _drop_empty(arr)
    n = round(float(arr.sum()))
    if min(kept.shape) < 2:
        why = "fewer than two non-empty rows or columns: independence is untestable"
        return ChiSquare(None, 0, None, n, dropped, why)
    from scipy.stats import chi2_contingency  # heavy: imported on first use

    res = chi2_contingency(kept, correction=False)
    return ChiSquare(float(res.statistic), int(res.dof), float(res.pvalue), n, dropped)


def _drop_empty(arr: np.ndarray) -> tuple[np.ndarray, tuple[str, ...]]:
    """``arr`` without its all-zero rows and columns, and their names (``row 2``, ``column 0``)."""
    rows, cols = arr.sum(axis=1) > 0, arr.sum(axis=0) > 0
    dropped = [f"row {i}" for i in np.flatnonzero(~rows)]
    dropped += [f"column {j}" for j in np.flatnonzero(~cols)]
    return arr[rows][:, cols], tuple(dropped)


@dataclass(frozen=True)
class FisherExact:
    """Two-sided Fisher exact test on a 2 x 2 table."""

    odds_ratio: float
    """Sample odds ratio ``(a d) / (b c)`` (``inf`` or ``nan`` with zero cells, as scipy)."""
    p_value: float


def fisher_exact_2x2(table: ArrayLike) -> FisherExact:
    """Two-sided Fisher exact test (:func:`scipy.stats.fisher_exact`) of a 2 x 2 count table.

    Rows are the reference and the compared group, columns the binary outcome (e.g. chose the
    Conference Room vs any other room). An all-zero row or column gives ``p = 1``.

    :param table: The 2 x 2 counts.
    :returns: A :class:`FisherExact`: odds ratio and two-sided p-value.
    """
    arr = _table(table, "table")
    if arr.shape != (2, 2):
        raise ConfigError(f"table shape={arr.shape} must be 2 x 2 for Fisher's exact test.")
    if np.any(arr != np.round(arr)):
        raise ConfigError(f"table={arr.tolist()} must hold whole counts for Fisher's exact test.")
    from scipy.stats import fisher_exact  # heavy: imported on first use

    res = fisher_exact(arr.astype(np.int64), alternative="two-sided")
    return FisherExact(float(res.statistic), float(res.pvalue))


def cramers_v(table: ArrayLike) -> float | None:
    r"""Cramer's V effect size of a k x c table (no bias correction).

    .. math::
        V = \sqrt{\frac{\chi^2}{N\,(\min(k, c) - 1)}}

    In [0, 1], from :func:`chi_square` (so all-zero rows and columns are dropped first and
    ``min(k, c)`` counts what is left); agrees with
    :func:`scipy.stats.contingency.association` (``method="cramer"``). An untestable table
    (fewer than two non-empty rows or columns) gives None.

    :param table: A k x c table of counts, as for :func:`chi_square`.
    :returns: ``V`` in [0, 1], or None for an untestable table.
    """
    res = chi_square(table)
    if res.statistic is None:
        return None
    arr = _table(table, "table")
    kept, _ = _drop_empty(arr)
    return math.sqrt(res.statistic / (float(arr.sum()) * (min(kept.shape) - 1)))


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

    :param groups: Group name -> its values.
    :returns: An :class:`Anova`: F, p-value, group sizes, or None with a reason.
    """
    finite = {name: [v for v in values if math.isfinite(v)] for name, values in groups.items()}
    clean = {name: np.asarray(v, dtype=float) for name, v in finite.items() if v}
    sizes = {name: len(v) for name, v in clean.items()}
    k, n = len(clean), sum(sizes.values())
    if k < 2:
        return Anova(None, None, 0.0, 0.0, sizes, "fewer than two conditions with finite values")
    if n == k:
        return Anova(None, None, k - 1.0, 0.0, sizes, "no within-condition variation")
    within = sum(float(np.sum((v - v.mean()) ** 2)) for v in clean.values())
    if within == 0.0:
        why = "every condition is constant: F is undefined"
        if np.ptp(np.concatenate(list(clean.values()))) == 0.0:
            why = "all values are identical: F is undefined"
        return Anova(None, None, k - 1.0, float(n - k), sizes, why)
    from statsmodels.stats.oneway import anova_oneway  # heavy: imported on first use

    res = anova_oneway(list(clean.values()), use_var="equal")
    return Anova(
        float(res.statistic), float(res.pvalue), float(res.df_num), float(res.df_denom), sizes
    )


def _spell_arrays(durations: ArrayLike, observed: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    t = np.asarray(durations, dtype=float).reshape(-1)
    e = np.asarray(observed, dtype=bool).reshape(-1)
    if t.shape != e.shape:
        raise ConfigError(
            f"durations (n={t.size}) and observed (n={e.size}) must have the same length."
        )
    if not np.all(np.isfinite(t)) or np.any(t <= 0):
        raise ConfigError(
            "durations must be finite and > 0 (a spell lasts at least one step); "
            "drop or fix the offending spells."
        )
    return t, e


def efc(durations: ArrayLike, observed: ArrayLike) -> float | None:
    r"""Ebbinghaus memory strength: the censored exponential MLE (Eq. SMLE).

    .. math::
        \overline{EFC} = \frac{\sum_{j=1}^{n} t_j}{d}

    ``t_j`` runs over every spell, forgotten or censored; ``d`` counts the forgetting events:
    the mean retention time (steps) of an exponential forgetting process under
    non-informative right-censoring. Edge cases: no spell gives None; spells but no event
    gives ``inf`` (nothing was ever forgotten).

    :param durations: Spell lengths ``t_j`` in steps.
    :param observed: True where the spell ended in forgetting (``delta_j = 1``), False if censored.
    :returns: ``EFC`` in steps; ``inf`` without events; None without spells.
    """
    t, e = _spell_arrays(durations, observed)
    if t.size == 0:
        return None
    d = int(e.sum())
    return math.fsum(t.tolist()) / d if d else math.inf


@dataclass(frozen=True)
class AnchoredKM:
    """A coverage-anchored Kaplan-Meier curve ``S(t) = C * prod (1 - d/n)``."""

    coverage: float
    """``C_X``: the anchor, ``S(0)``."""
    times: tuple[float, ...]
    """``0`` then every distinct spell duration, ascending."""
    survival: tuple[float, ...]
    """Anchored survival at each time (``survival[0] == coverage``)."""
    at_risk: tuple[int, ...]
    """``n_tau``: spells with duration ``>= tau`` (``at_risk[0]`` is every spell)."""
    events: tuple[int, ...]
    """``d_tau``: forgetting events at ``tau`` (``events[0] == 0``)."""
    ci_low: tuple[float, ...] = ()
    """Lower bound of the pointwise 95 % band at each time (Greenwood variance, lifelines'
    log(-log) interval, times ``C``); ``ci_high`` the upper. Equal to ``survival`` where
    the band is degenerate (before any event, and after the curve reaches 0)."""
    ci_high: tuple[float, ...] = ()

    @property
    def n(self) -> int:
        return self.at_risk[0]

    @property
    def event_times(self) -> tuple[float, ...]:
        """``0`` then every time with at least one forgetting event (where the curve steps)."""
        return tuple(t for t, d in zip(self.times, self.events, strict=True) if d or t == 0.0)

    def at(self, t: float) -> float:
        """Anchored survival at time ``t`` (right-continuous step function, ``S(t<0) = C``)."""
        return self.survival[max(bisect.bisect_right(self.times, t) - 1, 0)]


def anchored_km(
    durations: ArrayLike,
    observed: ArrayLike,
    *,
    coverage: float,
) -> AnchoredKM:
    r"""Coverage-anchored Kaplan-Meier estimate (Appendix B), fitted by lifelines.

    .. math::
        \hat{S}_{\mathcal{X}}(t) = C_{\mathcal{X}} \prod_{\tau \le t}
            \left(1 - \frac{d_\tau}{n_\tau}\right)

    The absolute probability that an object of the set is both discovered and still held
    ``t`` steps after leaving view. The product-limit factor and its 95 % Greenwood band
    (log(-log) scale) come from :class:`lifelines.KaplanMeierFitter` (a spell censored at
    ``tau`` is at risk at ``tau``), then are multiplied by the fixed anchor ``C``. Starts at
    ``C`` and never increases. Edge cases: no spells gives the single point ``(0, C)``; no
    events a flat curve at ``C``; ties are counted together. ``coverage`` must lie in
    [0, 1]; durations must be finite and > 0.

    :param durations: Spell lengths in steps, finite and > 0.
    :param observed: True for a forgetting event, False for a censored spell.
    :param coverage: The anchor ``C`` in [0, 1].
    :returns: An :class:`AnchoredKM`: timeline, anchored survival and its 95 % band.
    """
    check_range("coverage", coverage, 0.0, 1.0)
    t, e = _spell_arrays(durations, observed)
    c = float(coverage)
    if t.size == 0:
        return AnchoredKM(c, (0.0,), (c,), (0,), (0,), (c,), (c,))
    from lifelines import KaplanMeierFitter  # heavy: imported on first use

    fitter = KaplanMeierFitter().fit(t, event_observed=e)
    table = fitter.event_table
    factor = fitter.survival_function_.to_numpy()[:, 0]
    band = fitter.confidence_interval_survival_function_.to_numpy()
    low, high = (c * np.where(np.isfinite(band), band, factor[:, None])).T.tolist()
    return AnchoredKM(
        coverage=c,
        times=tuple(table.index.to_numpy(dtype=float).tolist()),
        survival=tuple((c * factor).tolist()),
        at_risk=tuple(table["at_risk"].to_numpy(dtype=int).tolist()),
        events=tuple(table["observed"].to_numpy(dtype=int).tolist()),
        ci_low=tuple(low),
        ci_high=tuple(high),
    )


#: Where R^2 compares the Ebbinghaus curve with the Kaplan-Meier curve (see ebbinghaus_fit).
R2_POINTS: Final[tuple[str, ...]] = ("durations", "steps", "events")


@dataclass(frozen=True)
class EbbinghausFit:
    """The Ebbinghaus curve ``R(t) = C exp(-t / EFC)`` and its fit to the anchored KM."""

    coverage: float
    """``C_X``."""
    efc: float | None
    """Memory strength (Eq. SMLE): None without spells, ``inf`` without events."""
    r2: float | None
    """Coefficient of determination of ``R`` against the anchored KM (may be negative)."""
    n_spells: int
    n_events: int
    reason: str | None = None
    points: str = "durations"
    """Evaluation points of ``r2`` (one of :data:`R2_POINTS`)."""


def ebbinghaus_fit(
    durations: ArrayLike,
    observed: ArrayLike,
    *,
    coverage: float,
    points: str = "durations",
) -> EbbinghausFit:
    r"""Memory strength (Eq. SMLE) and goodness of fit of Eq. EbbinghausFC against KM.

    .. math::
        R_{\mathcal{X}}(\delta) = C_{\mathcal{X}} \exp(-\delta / \overline{EFC}_{\mathcal{X}}),
        \qquad
        R^2 = 1 - \frac{\sum_t (\hat{S}(t) - R(t))^2}{\sum_t (\hat{S}(t) - \bar{S})^2}

    **Evaluation points** ``t`` (the paper names none): ``points="durations"`` (default) takes
    the KM curve's own timeline (every distinct spell duration, events and censoring times
    alike) without ``t = 0``: the only grid on which a planted hard window fits the
    exponential visibly worse (R^2 gap >= 0.1) than planted exponential decay of similar
    mean, which is what the paper reads R^2 for. ``"steps"`` takes every step
    ``0..max duration``; ``"events"`` takes ``t = 0`` and the event times only. The docs
    ("Where we interpret or depart from the paper") give each finding on each grid. ``EFC``
    is the MLE, not a least-squares fit, so ``R^2`` is a diagnostic: negative when a flat
    mean predicts the KM curve better than the exponential (abrupt forgetting). Edge cases:
    no spells -> efc and r2 None; no events -> efc ``inf`` (reason given), the curve flat at
    ``C``; a KM curve with no variation at the evaluation points -> r2 None with a reason.

    :param durations: Spell lengths in steps, as for :func:`anchored_km`.
    :param observed: Event flags, one per spell.
    :param coverage: The anchor ``C`` of both curves.
    :param points: Evaluation grid of ``R^2``: ``"durations"``, ``"steps"`` or ``"events"``.
    :returns: An :class:`EbbinghausFit`: EFC, ``R^2`` and the reason for any None or ``inf``.
    """
    check_choice("points", points, R2_POINTS)
    t, e = _spell_arrays(durations, observed)
    strength = efc(t, e)
    n_events = int(e.sum())
    if strength is None:
        why = "no spells: nothing left view mapped"
        return EbbinghausFit(coverage, None, None, 0, 0, why, points)
    km = anchored_km(t, e, coverage=coverage)
    if points == "events":
        grid = np.asarray(km.event_times)
    elif points == "durations":
        grid = np.asarray(km.times[1:])
    else:
        grid = np.arange(0.0, math.floor(km.times[-1]) + 1.0)
    s_hat = np.array([km.at(x) for x in grid])
    reason = None if n_events else "no forgetting event: memory strength is unbounded"
    ss_tot = float(np.sum((s_hat - s_hat.mean()) ** 2))  # every grid holds a point
    r2 = None
    if ss_tot > 1e-15:
        model = coverage * np.exp(-grid / strength)
        r2 = 1.0 - float(np.sum((s_hat - model) ** 2)) / ss_tot
    else:
        reason = reason or "the Kaplan-Meier curve does not vary: R^2 is undefined"
    return EbbinghausFit(coverage, strength, r2, len(t), n_events, reason, points)
