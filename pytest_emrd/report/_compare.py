"""``emrd report --compare``: what a release changed, per metric and cell, paired (pure).

Two sides are compared: two runs (same model names), or two model names (``--compare-models``,
within one run or across two). Within a cell (model x variant x condition) an episode of side
A is paired with the episode of side B that has the same spec up to the model: the same
condition, spawn room and episode index, hence the same world seed. Episodes without a
partner are counted (``unpaired``) and left out.

For every compared gate metric (:data:`COMPARED`) and cell:

* the value on each side over the pairs both sides define (``GATE_METRICS[name].compute``),
  and the difference ``B - A``;
* a seeded **paired bootstrap** over pairs (the same resampled pair indices on both sides):
  the percentile 95 % CI of ``B - A``;
* a two-sided p-value for "no difference" from the **paired sign-flip (randomisation)
  test**: under the null the two episodes of a pair are exchangeable, so each pair's sides
  are swapped at random and the metric's ``B - A`` recomputed;
  ``p = #{|d_swap| >= |d|} / 2^n`` over all ``2^n`` patterns when ``2^n <= R`` (exact),
  else ``(1 + #) / (R + 1)`` over ``R`` seeded random patterns. Unlike a bootstrap p-value
  it is valid for a handful of pairs (two pairs can never give p below 0.5, where a
  bootstrap says 0.004) and it is exactly 1 for identical pairs.
  ``R = max(N_RESAMPLES, ceil(10 m / ALPHA))`` for ``m`` tests, so the smallest
  Holm-adjusted p stays at or below ``ALPHA / 10`` however many cells are compared;
* the p-values of the whole comparison corrected together for multiple testing with Holm's
  step-down method (:func:`statsmodels.stats.multitest.multipletests`, ``method="holm"``,
  family-wise error ``ALPHA``);
* the smallest Holm-adjusted p the test could reach with its ``n`` pairs, whatever the data:
  ``min(1, m * p_min(n))`` for ``m`` tests, where ``p_min(n) = 2 / 2^n`` for the exact test
  (only the observed sign pattern and its mirror image are as extreme) and ``1 / (R + 1)``
  for ``R`` random patterns;
* a verdict: ``better`` / ``worse`` when the Holm-adjusted p is below ``ALPHA`` (the direction
  from ``GATE_METRICS[name].better``: ``higher`` or ``lower`` is better); ``inconclusive``
  when it is not and could not have been (the reachable p above is ``ALPHA`` or more: eight
  pairs that all moved the same way still give ``2 / 2^8 = 0.0078``, times ``m``); ``no
  change`` when the test could have found a difference and did not, or when every resample
  of ``B - A`` is exactly 0 (the same episodes on both sides); ``n/a`` when there is no
  test (undefined or unbounded value, fewer than two pairs, unbounded bootstrap
  distribution). The CI and the test can disagree for a few pairs; the verdict follows the
  test.

Pairing removes the between-world variance (spawn pose, layout) that an unpaired comparison
counts as noise, and a pair whose episodes are identical contributes exactly 0: the same
deterministic agent against itself gives ``B - A = 0``, p = 1 and ``no change`` everywhere.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from typing import Any, Final

import numpy as np

from pytest_emrd._serde import from_dict, to_dict
from pytest_emrd.metrics import GATE_METRICS, EpisodeMetrics, Estimate, as_episode_metrics
from pytest_emrd.metrics._stats import N_RESAMPLES
from pytest_emrd.report._build import group_cells
from pytest_emrd.trajectory import Trajectory

#: Family-wise error rate of the Holm correction.
ALPHA: Final = 0.05

Value = Callable[[EpisodeMetrics], float | bool | None]

#: Metrics averaged over episodes: name -> per-episode value (None: undefined, pair left out).
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
#: Verdicts, in the order the document explains them.
VERDICTS: Final[tuple[str, ...]] = ("better", "worse", "no change", "inconclusive", "n/a")

Pair = tuple[EpisodeMetrics, EpisodeMetrics]


@dataclass(frozen=True)
class Difference:
    """One metric of one cell on side A and side B, over paired episodes."""

    model: str
    """Model of side A (``model_b`` is side B's; equal when two runs are compared)."""
    variant: str
    condition: str
    metric: str
    a: Estimate
    """Side A over the pairs used (``n`` = pairs)."""
    b: Estimate
    diff: float | None
    """``b.value - a.value``; None when either is undefined or unbounded."""
    ci_low: float | None
    """Paired percentile bootstrap 95 % CI of ``diff``."""
    ci_high: float | None
    p_value: float | None
    """Two-sided paired sign-flip p-value of ``diff = 0`` (None without a test)."""
    p_holm: float | None
    """``p_value`` after Holm's correction across every test of the comparison."""
    verdict: str
    """``better``, ``worse``, ``no change``, ``inconclusive`` or ``n/a`` (module docstring)."""
    model_b: str
    unpaired: int = 0
    """Episodes of the cell on either side without a partner (left out)."""
    reason: str | None = None
    """Why there is no test (``verdict == 'n/a'``), or why it could not decide
    (``inconclusive``)."""
    pairs: int = 0
    """Pairs the metric is compared on (both episodes define it)."""
    p_reachable: float | None = None
    """The smallest Holm-adjusted p this test's pairs could give (None without a test)."""

    @property
    def significant(self) -> bool | None:
        """The Holm-adjusted test rejects ``diff = 0`` (None without a test)."""
        return None if self.p_holm is None else self.p_holm < ALPHA


@dataclass(frozen=True)
class Comparison:
    """Every :class:`Difference` of a comparison and what could not be compared."""

    run_a: str
    run_b: str
    differences: tuple[Difference, ...]
    only_a: tuple[str, ...]
    """Cells (``model/variant/condition``) only side A holds: not compared."""
    only_b: tuple[str, ...]
    rng_seed: int = 0
    n_resamples: int = N_RESAMPLES
    models: tuple[str, str] | None = None
    """``(model A, model B)`` when two model names are compared, else None."""
    alpha: float = ALPHA

    def to_dict(self) -> dict[str, Any]:
        return to_dict(self)

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> Comparison:
        return from_dict(cls, data)


def _pairs(a: Sequence[EpisodeMetrics], b: Sequence[EpisodeMetrics]) -> tuple[list[Pair], int]:
    """Episodes of a cell paired by (spawn, episode); the count of those left without one."""
    by_key = {(m.spec.spawn, m.spec.episode): m for m in b}
    pairs = [(m, by_key[k]) for m in a if (k := (m.spec.spawn, m.spec.episode)) in by_key]
    return pairs, len(a) + len(b) - 2 * len(pairs)


def _used(name: str, pairs: list[Pair]) -> list[Pair]:
    """The pairs a metric is compared on: both episodes define it."""
    if name == "errored_rate":
        return pairs
    kept = [(x, y) for x, y in pairs if not x.errored and not y.errored]
    if name in _MEANS:
        get = _MEANS[name]
        return [(x, y) for x, y in kept if get(x) is not None and get(y) is not None]
    return kept


def _columns(name: str, pairs: list[Pair]) -> tuple[np.ndarray, np.ndarray]:
    """Side A and side B as ``(2, n)`` rows over the pairs: numerator and denominator of the
    metric (a mean is a ratio with denominator 1)."""

    def side(k: int) -> np.ndarray:
        if name in _RATIOS:
            num, den = _RATIOS[name]
            return np.array([[num(p[k]) for p in pairs], [den(p[k]) for p in pairs]], float)
        get = _MEANS.get(name, lambda m: m.errored)
        values = [float(get(p[k])) for p in pairs]  # type: ignore[arg-type]
        return np.array([values, [1.0] * len(pairs)])

    return side(0), side(1)


def _ratio(x: np.ndarray) -> np.ndarray:
    """``sum num / sum den`` over the last axis of ``(2, ..., n)`` rows."""
    with np.errstate(divide="ignore", invalid="ignore"):
        return x[0].sum(axis=-1) / x[1].sum(axis=-1)


def _sign_flips(n: int, resamples: int, rng: np.random.Generator) -> tuple[np.ndarray, bool]:
    """Which pairs swap sides, and whether that is every pattern: all ``2**n`` patterns when
    there are at most ``resamples`` (an exact test), else ``resamples`` random ones."""
    if 2**n <= resamples:
        return (np.arange(2**n)[:, None] >> np.arange(n)) & 1 == 1, True
    return rng.random((resamples, n)) < 0.5, False


def _test(a: np.ndarray, b: np.ndarray, diff: float, rng_seed: int, resamples: int
          ) -> tuple[float, float, float] | str:  # fmt: skip
    """Paired bootstrap CI and sign-flip p of ``diff`` (module docstring), or why none."""
    rng = np.random.default_rng(rng_seed)
    n = a.shape[1]
    idx = rng.integers(0, n, size=(resamples, n))
    boot = _ratio(b[:, idx]) - _ratio(a[:, idx])
    if not np.all(np.isfinite(boot)):
        return "the bootstrap distribution is unbounded (resamples without any event): no test"
    low, high = (float(q) for q in np.percentile(boot, [2.5, 97.5]))
    swap, exact = _sign_flips(n, resamples, rng)
    flipped = _ratio(np.where(swap, a[:, None], b[:, None])) - _ratio(
        np.where(swap, b[:, None], a[:, None]))  # fmt: skip
    # identical pairs give flipped == diff == 0: every pattern is as extreme, p = 1
    extreme = np.count_nonzero(np.abs(flipped) >= abs(diff) - 1e-12)
    p = extreme / len(swap) if exact else (1 + extreme) / (len(swap) + 1)
    return low, high, float(p)


def _difference(
    key: tuple[str, str, str], model_b: str, name: str, a: Sequence[EpisodeMetrics],
    b: Sequence[EpisodeMetrics], rng_seed: int, resamples: int,
) -> Difference:  # fmt: skip
    pairs, unpaired = _pairs(a, b)
    used = _used(name, pairs)
    ea = GATE_METRICS[name].compute([x for x, _ in used], rng_seed=rng_seed)
    eb = GATE_METRICS[name].compute([y for _, y in used], rng_seed=rng_seed)

    def result(diff: float | None, low: float | None = None, high: float | None = None,
               p: float | None = None, why: str | None = None) -> Difference:  # fmt: skip
        return Difference(*key, name, ea, eb, diff, low, high, p, None, "n/a", model_b,
                          unpaired, why, len(used))  # fmt: skip

    if not pairs:
        return result(None, why="no paired episodes (same condition, spawn room and episode)")
    if not used:
        return result(None, why=_why_no_pair(name, pairs))
    if ea.value is None or eb.value is None:
        undefined = ea if ea.value is None else eb
        return result(None, why=f"undefined in every pair ({undefined.reason})")
    if math.isinf(ea.value) or math.isinf(eb.value):
        side = "both sides" if math.isinf(ea.value) and math.isinf(eb.value) else "one side"
        return result(None, why=f"unbounded on {side} (no forgetting event)")
    diff = eb.value - ea.value
    if len(used) < 2:
        return result(diff, why="fewer than two pairs: no test")
    tested = _test(*_columns(name, used), diff, rng_seed, resamples)
    if isinstance(tested, str):
        return result(diff, why=tested)
    return result(diff, *tested)


def _why_no_pair(name: str, pairs: list[Pair]) -> str:
    """Why no pair defines ``name``: errored episodes, or the metric's own reason."""
    clean = [(x, y) for x, y in pairs if not x.errored and not y.errored]
    if not clean:
        return "every pair holds an errored episode"
    get = _MEANS.get(name)
    undefined = [m for pair in clean for m in pair if get is not None and get(m) is None]
    why = dict.fromkeys(m.reasons.get(name, "undefined") for m in undefined)
    return f"undefined in every pair: {'; '.join(why) or 'no value'}"


def smallest_p(n: int, resamples: int) -> float:
    """The smallest two-sided sign-flip p that ``n`` pairs can give (module docstring):
    ``2 / 2^n`` when every pattern is enumerated, ``1 / (R + 1)`` over ``R`` random ones."""
    return 2.0 / 2**n if 2**n <= resamples else 1.0 / (resamples + 1)


def _verdict(d: Difference, p_holm: float, reachable: float) -> Difference:
    better = GATE_METRICS[d.metric].better
    verdict, why = "no change", d.reason
    if p_holm < ALPHA and d.diff:
        verdict = "better" if (d.diff > 0) == (better == "higher") else "worse"
    elif reachable >= ALPHA and not d.diff == d.ci_low == d.ci_high == 0:  # not identical
        verdict = "inconclusive"
        why = (f"{d.pairs} pairs cannot reach Holm p < {ALPHA}: the smallest reachable is "
               f"{reachable:.3g}; more episodes per cell can")  # fmt: skip
    return replace(d, p_holm=p_holm, verdict=verdict, p_reachable=reachable, reason=why)


def holm(differences: Sequence[Difference], resamples: int = N_RESAMPLES) -> tuple[Difference, ...]:
    """Holm-adjust every p-value of ``differences`` together and set the verdicts
    (``resamples``: the sign-flip test's pattern budget, for the reachable p)."""
    tested = [i for i, d in enumerate(differences) if d.p_value is not None]
    out = list(differences)
    if tested:
        from statsmodels.stats.multitest import multipletests  # heavy: imported on first use

        adjusted = multipletests([differences[i].p_value for i in tested], alpha=ALPHA,
                                 method="holm")[1]  # fmt: skip
        for i, p in zip(tested, adjusted, strict=True):
            d = differences[i]
            reachable = min(1.0, len(tested) * smallest_p(d.pairs, resamples))
            out[i] = _verdict(d, float(p), reachable)
    return tuple(out)


def compare_runs(
    run_a: Sequence[Trajectory],
    run_b: Sequence[Trajectory],
    *,
    names: tuple[str, str] = ("A", "B"),
    models: tuple[str, str] | None = None,
    rng_seed: int = 0,
) -> Comparison:
    """Paired comparison of ``run_b`` against ``run_a`` (see the module docstring).

    ``models=(A, B)`` compares model ``A`` of ``run_a`` with model ``B`` of ``run_b`` (pass
    the same trajectories twice to compare two models of one run); without it, cells are
    matched by model name.
    """
    cells_a = group_cells(as_episode_metrics(run_a))
    cells_b = group_cells(as_episode_metrics(run_b))
    if models is not None:
        cells_a = {(models[0], *k[1:]): v for k, v in cells_a.items() if k[0] == models[0]}
        cells_b = {(models[0], *k[1:]): v for k, v in cells_b.items() if k[0] == models[1]}
    model_b = (lambda k: models[1]) if models is not None else (lambda k: k[0])
    shared = [k for k in cells_a if k in cells_b]
    resamples = max(N_RESAMPLES, math.ceil(10 * len(shared) * len(COMPARED) / ALPHA))
    diffs = tuple(
        _difference(k, model_b(k), name, cells_a[k], cells_b[k], rng_seed, resamples)
        for k in shared
        for name in COMPARED
    )

    def cell(k: tuple[str, str, str], side: int) -> str:
        return "/".join((models[side] if models else k[0], *k[1:]))

    return Comparison(
        names[0], names[1], holm(diffs, resamples),
        tuple(cell(k, 0) for k in cells_a if k not in cells_b),
        tuple(cell(k, 1) for k in cells_b if k not in cells_a),
        rng_seed, resamples, models,
    )  # fmt: skip
