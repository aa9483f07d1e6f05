"""The gate-metric registry: the names thresholds.yaml may use, each with its estimator.

Every ``compute(items, *, rng_seed=0) -> Estimate`` accepts trajectories or
:class:`EpisodeMetrics` (pass the latter to evaluate many gates without re-matching), excludes
errored episodes (counted in ``excluded``) and attaches a seeded percentile bootstrap 95 % CI
(:func:`bootstrap_ci`; resampling *episodes*, also for pooled ratios). Fractions are in
[0, 1], never percent.
"""

from __future__ import annotations

import functools
import json
import math
import statistics
from collections import Counter
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from importlib import resources
from types import MappingProxyType
from typing import Final, Literal, Protocol

import numpy as np

from pytest_emrd.errors import check_choice
from pytest_emrd.metrics._aggregates import consensus, pooled_fit
from pytest_emrd.metrics._episode import (
    EpisodeLike,
    EpisodeMetrics,
    as_episode_metrics,
    split_errored,
)
from pytest_emrd.metrics._stats import (
    N_RESAMPLES,
    Estimate,
    bootstrap_ci,
    draw_counts,
    resample_rows,
)
from pytest_emrd.rooms import FOCAL_COLUMNS, OTHER_LETTER


class Compute(Protocol):
    def __call__(self, items: Sequence[EpisodeLike], *, rng_seed: int = 0) -> Estimate: ...


@dataclass(frozen=True)
class GateMetric:
    """A metric thresholds.yaml can gate on."""

    name: str
    description: str
    better: Literal["higher", "lower"]
    unit: str
    """``fraction`` (in [0, 1]), ``steps`` or ``R^2``."""
    compute: Compute


def _estimate(name: str, items: Sequence[EpisodeLike], *, rng_seed: int = 0) -> Estimate:
    """Gate metric ``name`` over the non-errored episodes (the errored ones are ``excluded``)."""
    kept, errored = split_errored(items)
    if not kept:
        return Estimate(None, None, None, 0, "no non-errored episode", errored)
    if name == "ebbinghaus_r2":
        return _r2(kept, errored, rng_seed)
    if name == "consensus":
        return _consensus(kept, errored, rng_seed)
    if name in RATIO_METRICS:
        return _ratio(name, kept, errored, rng_seed)
    return _mean(name, kept, errored, rng_seed)


def _mean(name: str, kept: list[EpisodeMetrics], errored: int, rng_seed: int) -> Estimate:
    """Mean over episodes of the per-episode score ``name`` (where defined)."""
    values = [float(v) for m in kept if (v := getattr(m, name)) is not None]
    excluded = errored + len(kept) - len(values)
    if not values:
        reasons = Counter(m.reasons.get(name, "undefined") for m in kept)
        why = f"undefined in every episode ({reasons.most_common(1)[0][0]})"
        return Estimate(None, None, None, 0, why, excluded)
    low, high = bootstrap_ci(values, rng_seed=rng_seed)
    reason = None if low is not None else "one episode: no confidence interval"
    return Estimate(statistics.fmean(values), low, high, len(values), reason, excluded)


def _ratio(name: str, kept: list[EpisodeMetrics], errored: int, rng_seed: int) -> Estimate:
    """Pooled ``sum num / sum den`` of two per-episode counts (:data:`RATIO_METRICS`),
    bootstrapped by episode."""
    num, den = RATIO_METRICS[name]
    pairs = np.array([(getattr(m, num), getattr(m, den)) for m in kept], dtype=float)
    total_num, total_den = pairs.sum(axis=0)
    if total_den == 0 and total_num == 0:
        why = kept[0].reasons.get(name) or f"{name} has an empty denominator"
        return Estimate(None, None, None, len(kept), why, errored)

    def ratio(rows: np.ndarray) -> np.ndarray:  # exact sums: the counts are whole numbers
        sums = rows.sum(axis=1)
        return sums[:, 0] / sums[:, 1]

    low, high = bootstrap_ci(pairs, ratio, rng_seed=rng_seed)
    if total_den == 0:
        reason = f"{name}: no event in any episode, the estimate is unbounded"
        return Estimate(math.inf, low, high, len(kept), reason, errored)
    return Estimate(float(total_num / total_den), low, high, len(kept), None, errored)


def _consensus(kept: list[EpisodeMetrics], errored: int, rng_seed: int) -> Estimate:
    """:func:`consensus` share, bootstrapped over episodes."""
    rooms = [c for c in FOCAL_COLUMNS if c != OTHER_LETTER]
    chose = np.array([[m.chosen_letter == c for c in rooms] for m in kept], dtype=float)

    def share(rows: np.ndarray) -> np.ndarray:
        return rows.sum(axis=1).max(axis=1) / len(kept)

    low, high = bootstrap_ci(chose, share, rng_seed=rng_seed)
    return Estimate(consensus(kept).share, low, high, len(kept), None, errored)


def _r2(kept: list[EpisodeMetrics], errored: int, rng_seed: int) -> Estimate:
    """Pooled R^2 (value from :func:`ebbinghaus_fit`); CI from resampled episode histograms."""
    full = pooled_fit(kept, None)
    if full.r2 is None:
        return Estimate(None, None, None, len(kept), full.reason, errored)
    if len(kept) < 2:
        return Estimate(full.r2, None, None, 1, "one episode: no confidence interval", errored)
    # Per episode, the first spells ending at each duration, and the events among them.
    cells = np.array(
        [(i, s.duration, s.forgotten) for i, m in enumerate(kept) for s in m.ttf_spells]
    )
    at = (cells[:, 0], cells[:, 1])
    leave, death = np.zeros((2, len(kept), cells[:, 1].max() + 1))
    np.add.at(leave, at, 1.0)
    np.add.at(death, at, cells[:, 2])
    mapped = np.array([sum(m.mapped_by_category.values()) for m in kept], dtype=float)
    total = np.array([sum(m.objects_by_category.values()) for m in kept], dtype=float)
    weights = draw_counts(resample_rows(rng_seed, len(kept), N_RESAMPLES))
    draws = _r2_of_histograms(weights @ leave, weights @ death, weights @ mapped, weights @ total)
    draws = draws[np.isfinite(draws)]
    if not len(draws):
        return Estimate(full.r2, None, None, len(kept), "R^2 undefined in every resample", errored)
    low, high = np.quantile(draws, [0.025, 0.975])
    return Estimate(full.r2, float(low), float(high), len(kept), None, errored)


def _r2_of_histograms(
    leave: np.ndarray, death: np.ndarray, mapped: np.ndarray, total: np.ndarray
) -> np.ndarray:
    """:func:`ebbinghaus_fit`'s R^2 for many pooled samples given as duration histograms.

    Row ``r`` holds, per duration ``t``, the spells ending at ``t`` (``leave``) and the events
    among them (``death``). Same evaluation points (the default ``"durations"``: every
    duration present), anchor, MLE and R^2 as the scalar function; NaN where R^2 is undefined.
    """
    t = np.arange(leave.shape[1], dtype=float)
    with np.errstate(divide="ignore", invalid="ignore"):
        at_risk = leave.sum(axis=1, keepdims=True) - np.cumsum(leave, axis=1) + leave
        factor = np.where(at_risk > 0, 1.0 - death / at_risk, 1.0)
        coverage = np.where(total > 0, mapped / total, 0.0)[:, None]
        s_hat = coverage * np.cumprod(factor, axis=1)
        strength = (leave * t).sum(axis=1) / death.sum(axis=1)
        model = coverage * np.exp(-t[None, :] / strength[:, None])
        present = leave > 0
        n = present.sum(axis=1)
        mean = np.where(present, s_hat, 0.0).sum(axis=1) / n
        ss_tot = np.where(present, (s_hat - mean[:, None]) ** 2, 0.0).sum(axis=1)
        ss_res = np.where(present, (s_hat - model) ** 2, 0.0).sum(axis=1)
        r2 = 1.0 - ss_res / ss_tot
    return np.where(ss_tot > 1e-15, r2, np.nan)


def _errored_rate(items: Sequence[EpisodeLike], *, rng_seed: int = 0) -> Estimate:
    flags = [float(m.errored) for m in as_episode_metrics(items)]
    if not flags:
        return Estimate(None, None, None, 0, "no episode")
    low, high = bootstrap_ci(flags, rng_seed=rng_seed)
    return Estimate(statistics.fmean(flags), low, high, len(flags))


#: Pooled ratios among the gate metrics: name -> (numerator, denominator) EpisodeMetrics fields.
RATIO_METRICS: Final[Mapping[str, tuple[str, str]]] = {
    "memory_strength": ("retained_steps", "forget_events"),
    "parse_failure_rate": ("parse_failures", "steps"),
}


def _estimator(name: str) -> Compute:
    if name == "errored_rate":
        return _errored_rate
    return functools.partial(_estimate, name)


#: Metric name -> gate metric. thresholds.yaml metric names must be keys of this mapping. Name,
#: description, direction and unit of each are data (``gate_metrics.json`` beside this module).
GATE_METRICS: Mapping[str, GateMetric] = MappingProxyType(
    {
        name: GateMetric(name, *row, _estimator(name))
        for name, row in json.loads(
            resources.files(__package__).joinpath("gate_metrics.json").read_text("utf-8")
        ).items()
    }
)


def evaluate_gates(
    items: Sequence[EpisodeLike], names: Iterable[str] | None = None, *, rng_seed: int = 0
) -> dict[str, Estimate]:
    """Compute several gate metrics over the same episodes, matching each episode once.

    ``names`` defaults to every registered metric; an unknown name raises ConfigError.

    :param items: Trajectories or :class:`EpisodeMetrics`, matched once and shared.
    :param names: Gate metrics of :data:`GATE_METRICS` to compute; None for all.
    :param rng_seed: Seed of every metric's bootstrap CI.
    :returns: Metric name -> its :class:`Estimate`, in ``names`` order.
    """
    selected = list(GATE_METRICS) if names is None else list(names)
    for name in selected:
        check_choice("metric", name, GATE_METRICS, hint="See pytest_emrd.metrics.GATE_METRICS.")
    metrics = as_episode_metrics(items)
    return {name: GATE_METRICS[name].compute(metrics, rng_seed=rng_seed) for name in selected}
