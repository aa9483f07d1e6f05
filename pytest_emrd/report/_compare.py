"""``emrd report --compare``: what a release changed, per metric and cell, paired (pure).

Side A and side B are two runs (same model names) or two model names (``--compare-models``).
Within a cell (model x variant x condition) an episode of A is paired with the episode of B of
the same condition, spawn room and episode index (the same world); the others are counted
(``unpaired``) and left out. Per compared gate metric (:data:`COMPARED`), over the pairs that
define it: both values and ``B - A``; a seeded paired-bootstrap percentile 95 % CI; a
two-sided paired sign-flip p, ``#{|d_swap| >= |d|} / 2^n`` over every pattern when
``2^n <= R`` (exact), else ``(1 + #) / (R + 1)`` over ``R`` seeded random ones, where
``R = max(N_RESAMPLES, ceil(10 m / ALPHA))`` for ``m`` tests keeps the smallest Holm p at or
below ``ALPHA / 10`` (unlike a bootstrap p it is valid for a few pairs, and 1 for identical
ones); Holm's correction across the whole comparison; and the smallest Holm p the pairs could
reach, ``min(1, m * p_min(n))`` with ``p_min(n) = 2 / 2^n`` (exact) or ``1 / (R + 1)``.

Verdict: ``better`` / ``worse`` when the Holm p < ``ALPHA`` (direction from
``GATE_METRICS[name].better``); ``inconclusive`` when it is not and could not have been
(reachable p >= ``ALPHA``); ``no change`` when the test could have found a difference and did
not, or when every resample of ``B - A`` is 0; ``n/a`` without a test (undefined or unbounded
value, fewer than two pairs, unbounded bootstrap). The verdict follows the test, not the CI.
TE is read alongside AEC (the paper): a TE ``better`` in a cell whose AEC fell is ``flagged``
(the run quit earlier and covered less).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import Final

import numpy as np

from pytest_emrd._serde import JsonRecord
from pytest_emrd.metrics import (
    GATE_METRICS,
    N_RESAMPLES,
    RATIO_METRICS,
    EpisodeMetrics,
    Estimate,
    as_episode_metrics,
)
from pytest_emrd.report._build import group_cells
from pytest_emrd.report._document import (
    Block,
    Bullets,
    Cell,
    Document,
    Paragraph,
    Row,
    Section,
    Table,
    num,
    pval,
)
from pytest_emrd.report._model import CONDITION_NAMES, row_label
from pytest_emrd.trajectory import Trajectory

#: Family-wise error rate of the Holm correction.
ALPHA: Final = 0.05

#: Metrics averaged over episodes, each the EpisodeMetrics field of the same name (None:
#: undefined, pair left out).
_MEANS: Final = (
    "aec",
    "grounded_aec",
    "ungrounded_rate",
    "te",
    "pa",
    "fpsg_local",
    "fpsg_global",
    "never_visited",
    "any_bias",
    "sir",
)
#: Compared metrics, in report order (every one a key of GATE_METRICS).
COMPARED: Final[tuple[str, ...]] = (*_MEANS, *RATIO_METRICS, "errored_rate")

Pair = tuple[EpisodeMetrics, EpisodeMetrics]


@dataclass(frozen=True, kw_only=True)
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
    diff: float | None = None
    """``b.value - a.value``; None when either is undefined or unbounded."""
    ci_low: float | None = None
    """Paired percentile bootstrap 95 % CI of ``diff``."""
    ci_high: float | None = None
    p_value: float | None = None
    """Two-sided paired sign-flip p-value of ``diff = 0`` (None without a test)."""
    p_holm: float | None = None
    """``p_value`` after Holm's correction across every test of the comparison."""
    verdict: str = "n/a"
    """``better``, ``worse``, ``no change``, ``inconclusive``, ``flagged`` or ``n/a`` (module
    docstring)."""
    model_b: str
    unpaired: int = 0
    """Episodes of the cell on either side without a partner (left out)."""
    reason: str | None = None
    """Why there is no test (``n/a``), or why it could not decide (``inconclusive``)."""
    pairs: int = 0
    """Pairs the metric is compared on (both episodes define it)."""
    p_reachable: float | None = None
    """The smallest Holm-adjusted p this test's pairs could give (None without a test)."""

    @property
    def label(self) -> str:
        """The compared model row: ``scout [B3]``, or ``scout vs gemini`` for two models."""
        who = self.model if self.model == self.model_b else f"{self.model} vs {self.model_b}"
        return row_label(who, self.variant)

    @property
    def significant(self) -> bool | None:
        """The Holm-adjusted test rejects ``diff = 0`` (None without a test)."""
        return None if self.p_holm is None else self.p_holm < ALPHA


@dataclass(frozen=True, kw_only=True)
class Comparison(JsonRecord):
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
        return [(x, y) for x, y in kept if None not in (getattr(x, name), getattr(y, name))]
    return kept


def _columns(name: str, pairs: list[Pair]) -> tuple[np.ndarray, np.ndarray]:
    """Side A and side B as ``(2, n)`` rows over the pairs: numerator and denominator of the
    metric (a mean is a ratio with denominator 1)."""

    def side(k: int) -> np.ndarray:
        if name in RATIO_METRICS:
            return np.array([[getattr(p[k], f) for p in pairs] for f in RATIO_METRICS[name]], float)
        field = name if name in _MEANS else "errored"
        return np.array([[float(getattr(p[k], field)) for p in pairs], [1.0] * len(pairs)])

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


def _test(
    a: np.ndarray, b: np.ndarray, diff: float, rng_seed: int, resamples: int
) -> tuple[float, float, float] | str:
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
        np.where(swap, b[:, None], a[:, None])
    )
    # identical pairs give flipped == diff == 0: every pattern is as extreme, p = 1
    extreme = np.count_nonzero(np.abs(flipped) >= abs(diff) - 1e-12)
    p = extreme / len(swap) if exact else (1 + extreme) / (len(swap) + 1)
    return low, high, float(p)


def _difference(
    key: tuple[str, str, str],
    model_b: str,
    name: str,
    a: Sequence[EpisodeMetrics],
    b: Sequence[EpisodeMetrics],
    rng_seed: int,
    resamples: int,
) -> Difference:
    pairs, unpaired = _pairs(a, b)
    used = _used(name, pairs)
    ea, eb = (GATE_METRICS[name].compute([p[k] for p in used], rng_seed=rng_seed) for k in (0, 1))

    untested = Difference(  # verdict n/a; holm() sets the verdict of a tested one
        model=key[0],
        variant=key[1],
        condition=key[2],
        metric=name,
        a=ea,
        b=eb,
        model_b=model_b,
        unpaired=unpaired,
        pairs=len(used),
    )
    if not pairs:
        return replace(
            untested, reason="no paired episodes (same condition, spawn room and episode)"
        )
    if not used:
        return replace(untested, reason=_why_no_pair(name, pairs))
    if ea.value is None or eb.value is None:
        undefined = ea if ea.value is None else eb
        return replace(untested, reason=f"undefined in every pair ({undefined.reason})")
    if math.isinf(ea.value) or math.isinf(eb.value):
        side = "both sides" if math.isinf(ea.value) and math.isinf(eb.value) else "one side"
        return replace(untested, reason=f"unbounded on {side} (no forgetting event)")
    diff = eb.value - ea.value
    if len(used) < 2:
        return replace(untested, diff=diff, reason="fewer than two pairs: no test")
    tested = _test(*_columns(name, used), diff, rng_seed, resamples)
    if isinstance(tested, str):
        return replace(untested, diff=diff, reason=tested)
    low, high, p = tested
    return replace(untested, diff=diff, ci_low=low, ci_high=high, p_value=p)


def _why_no_pair(name: str, pairs: list[Pair]) -> str:
    """Why no pair defines ``name`` (a mean: a pooled ratio is defined on every clean pair):
    errored episodes, or the metric's own reason."""
    clean = [m for x, y in pairs if not x.errored and not y.errored for m in (x, y)]
    if not clean:
        return "every pair holds an errored episode"
    why = dict.fromkeys(m.reasons.get(name, "undefined") for m in clean if getattr(m, name) is None)
    return f"undefined in every pair: {'; '.join(why)}"


def _verdict(d: Difference, p_holm: float, reachable: float) -> Difference:
    better = GATE_METRICS[d.metric].better
    verdict, why = "no change", d.reason
    if p_holm < ALPHA and d.diff:
        verdict = "better" if (d.diff > 0) == (better == "higher") else "worse"
    elif reachable >= ALPHA and not d.diff == d.ci_low == d.ci_high == 0:  # not identical
        verdict = "inconclusive"
        why = (
            f"{d.pairs} pairs cannot reach Holm p < {ALPHA}: the smallest reachable is "
            f"{reachable:.3g}; more episodes per cell can"
        )
    return replace(d, p_holm=p_holm, verdict=verdict, p_reachable=reachable, reason=why)


def holm(differences: Sequence[Difference], resamples: int = N_RESAMPLES) -> tuple[Difference, ...]:
    """Holm-adjust every p-value of ``differences`` together and set the verdicts
    (``resamples``: the sign-flip test's pattern budget, for the reachable p)."""
    tested = [i for i, d in enumerate(differences) if d.p_value is not None]
    out = list(differences)
    if tested:
        from statsmodels.stats.multitest import multipletests  # heavy: imported on first use

        adjusted = multipletests(
            [differences[i].p_value for i in tested], alpha=ALPHA, method="holm"
        )[1]
        for i, p in zip(tested, adjusted, strict=True):
            n = differences[i].pairs  # the smallest p its pairs can give: p_min(n)
            p_min = 2.0 / 2**n if 2**n <= resamples else 1.0 / (resamples + 1)
            out[i] = _verdict(differences[i], float(p), min(1.0, len(tested) * p_min))
    return tuple(out)


def _te_with_aec(diffs: tuple[Difference, ...]) -> tuple[Difference, ...]:
    """A TE that improved (fewer actions) read with the cell's AEC, as the paper reads TE: when
    coverage fell too, the run quit earlier and saw less, ``flagged`` rather than ``better``."""
    aec = {(d.model, d.variant, d.condition): d.diff for d in diffs if d.metric == "aec"}
    out = list(diffs)
    for i, d in enumerate(diffs):
        drop = aec.get((d.model, d.variant, d.condition))
        if d.metric == "te" and d.verdict == "better" and drop is not None and drop < 0:
            why = f"fewer actions but AEC fell by {-drop:.3g}: it quit earlier and covered less"
            out[i] = replace(d, verdict="flagged", reason=f"{why}; TE is read alongside AEC")
    return tuple(out)


def compare_lines(c: Comparison) -> list[str]:
    """One terminal line per metric and cell: both values, ``B - A`` with its CI, the Holm p
    and the verdict (and why, when there is a reason).

    :param c: The comparison.
    :returns: The lines, without newlines.
    """
    lines = []
    for d in c.differences:
        ci = "" if d.ci_low is None else f" [{num(d.ci_low)}, {num(d.ci_high)}]"
        why = f" ({d.reason})" if d.reason and d.verdict != "no change" else ""
        lines.append(
            f"{d.label} {d.condition} {d.metric}: {num(d.a.value)} -> "
            f"{num(d.b.value)}, B - A {num(d.diff)}{ci}, Holm p {pval(d.p_holm)}: "
            f"{d.verdict}{why}"
        )
    return lines


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

    :param run_a: The reference run's trajectories.
    :param run_b: The compared run's trajectories.
    :param names: How the two runs are named in the output.
    :param models: ``(A, B)``, the model of each run to compare; None to match by name.
    :param rng_seed: Seed of the bootstrap CIs.
    :returns: The :class:`Comparison`.
    """
    cells_a, cells_b = (group_cells(as_episode_metrics(run)) for run in (run_a, run_b))
    if models is not None:  # side B's cells keyed by model A, as side A's
        cells_a = {k: v for k, v in cells_a.items() if k[0] == models[0]}
        cells_b = {(models[0], *k[1:]): v for k, v in cells_b.items() if k[0] == models[1]}
    shared = [k for k in cells_a if k in cells_b]
    resamples = max(N_RESAMPLES, math.ceil(10 * len(shared) * len(COMPARED) / ALPHA))

    def model_b(k: tuple[str, str, str]) -> str:
        return models[1] if models else k[0]

    diffs = tuple(
        _difference(k, model_b(k), name, cells_a[k], cells_b[k], rng_seed, resamples)
        for k in shared
        for name in COMPARED
    )
    return Comparison(
        run_a=names[0],
        run_b=names[1],
        differences=_te_with_aec(holm(diffs, resamples)),
        only_a=tuple("/".join(k) for k in cells_a if k not in cells_b),
        only_b=tuple("/".join((model_b(k), *k[1:])) for k in cells_b if k not in cells_a),
        rng_seed=rng_seed,
        n_resamples=resamples,
        models=models,
    )


_HEADER = ("Metric", "Better", "A", "B", "B - A", "95% CI", "p (Holm)", "Verdict", "Note")


def _row(d: Difference) -> Row:
    note = d.reason or ""
    if d.unpaired:
        note = f"{d.unpaired} unpaired episode(s) left out. {note}".strip()
    ci = "n/a" if d.ci_low is None else f"[{num(d.ci_low)}, {num(d.ci_high)}]"
    return (
        d.metric,
        GATE_METRICS[d.metric].better,
        f"{num(d.a.value)} (n={d.a.n})",
        f"{num(d.b.value)} (n={d.b.n})",
        num(d.diff),
        ci,
        pval(d.p_holm),
        Cell(d.verdict, bold=d.verdict != "no change"),
        note,
    )


def compare_document(c: Comparison) -> Document:
    """Per cell: metric, direction, value on each side, B - A, CI, Holm p and verdict."""
    sides = f"A = {c.run_a}, B = {c.run_b}"
    if c.models is not None:
        sides = f"A = model {c.models[0]} of {c.run_a}, B = model {c.models[1]} of {c.run_b}"
    blocks: list[Block] = [
        Paragraph(
            f"{sides}. Episodes are paired by condition, spawn room and episode index (same "
            f"world). B - A over the pairs; 95% CI from a seeded (rng_seed={c.rng_seed}) paired "
            f"bootstrap ({c.n_resamples} resamples); two-sided p from a paired sign-flip test "
            f"(exact up to {c.n_resamples} patterns), Holm-corrected across all "
            f"{sum(d.p_value is not None for d in c.differences)} tests. Verdict **better** / "
            f"**worse** when the Holm p < {c.alpha} (direction: the Better column); "
            "**inconclusive** when it is not and the pairs could not have made it so (the "
            "Note gives the smallest Holm p they could reach): run more episodes before "
            "reading it as no change; else no change; n/a without a test."
        )
    ]
    if c.only_a or c.only_b:
        notes = [f"only in A (not compared): {k}" for k in c.only_a]
        notes += [f"only in B (not compared): {k}" for k in c.only_b]
        blocks.append(Bullets(notes))
    if not c.differences:
        blocks.append(Paragraph("The two sides share no model x prompt x condition cell."))
    by_cell: dict[tuple[str, str], list[Row]] = {}  # (table id, caption) -> rows
    for d in c.differences:
        table_id = f"compare-{d.model}-{d.model_b}-{d.variant}-{d.condition}"
        caption = f"{d.label}, {CONDITION_NAMES.get(d.condition, d.condition)}"
        by_cell.setdefault((table_id, caption), []).append(_row(d))
    blocks += [Table(*key, _HEADER, rows) for key, rows in by_cell.items()]
    return Document("EMRD comparison", [Section("compare", "Differences", blocks)])
