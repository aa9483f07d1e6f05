"""Gate verdicts: a metric's estimate over a cell's episodes (model x condition x prompt
variant x layouts), compared with its bound (pure). Episodes are sorted by case id and the
bootstrap is seeded (``rng_seed=0``): the same episodes give the same verdict anywhere."""

from __future__ import annotations

import math
import shlex
from collections import defaultdict
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, Any, Final

from pytest_emrd._serde import JsonRecord
from pytest_emrd.gate._thresholds import Bound, Thresholds

if TYPE_CHECKING:
    from pytest_emrd.metrics import Estimate, GateMetric


@dataclass(frozen=True)
class GateCell:
    """One gate test: a bound applied to the episodes of model x condition x variant x layouts
    (the bound's: paper-protocol and generated-layout episodes never share a cell)."""

    bound: Bound
    variant: str = "default"

    @property
    def gate_id(self) -> str:
        """``scout-baseline-aec`` (variant, then ``generated``, inserted when not default)."""
        b = self.bound
        return _gate_id(b.model, b.condition, self.variant, b.layouts, b.metric)


def _gate_id(model: str, condition: str, variant: str, layouts: str, metric: str) -> str:
    named = [
        name for name, default in ((variant, "default"), (layouts, "paper")) if name != default
    ]
    return "-".join([model, condition, *named, metric])


@dataclass(frozen=True)
class Verdict(JsonRecord):
    """The outcome of one gate."""

    model: str
    condition: str
    variant: str
    metric: str
    kind: str
    bound: float
    ci: str | None
    """Which end of the CI was compared (``None``: the point value)."""
    value: float | None
    ci_low: float | None
    ci_high: float | None
    n: int
    passed: bool
    reason: str
    """Why it passed or failed, in one sentence."""
    layouts: str = "paper"
    worst: tuple[tuple[str, float], ...] = ()
    """A failed gate's worst episodes (case id, the metric's value there), worst first."""
    view: str = ""
    """The ``emrd view`` command that opens :attr:`worst` (empty when none is known)."""

    @property
    def gate_id(self) -> str:
        return _gate_id(self.model, self.condition, self.variant, self.layouts, self.metric)

    @property
    def cell_label(self) -> str:
        """``baseline``, ``baseline/B3``, ``baseline@generated``: the cell in gate tables."""
        label = self.condition if self.variant == "default" else f"{self.condition}/{self.variant}"
        return label if self.layouts == "paper" else f"{label}@{self.layouts}"

    @property
    def bound_text(self) -> str:
        op = ">=" if self.kind == "min" else "<="
        side = f" (CI {self.ci})" if self.ci else ""
        return f"{op} {self.bound:g}{side}"

    def evidence(self) -> list[str]:
        """A failed gate's worst episodes and the command that opens them (none when passed)."""
        if self.passed or not self.worst:
            return []
        listed = ", ".join(f"{case} ({value:.4g})" for case, value in self.worst)
        return [f"worst episodes by {self.metric}: {listed}", f"open them: `{self.view}`"]

    def explain(self) -> str:
        """``scout-baseline-aec: value 0.912 [0.88, 0.94] n=80, bound >= 0.8: PASS (...)``."""
        ci = f"[{format_number(self.ci_low)}, {format_number(self.ci_high)}]"
        return (
            f"{self.gate_id}: value {format_number(self.value)} {ci}"
            f" n={self.n}, bound {self.bound_text}: {'PASS' if self.passed else 'FAIL'}"
            f" ({self.reason})"
        )


def format_number(x: float | None) -> str:
    """Four significant digits, ``n/a`` for an undefined value."""
    return "n/a" if x is None else f"{x:.4g}"


def judge(cell: GateCell, estimate: Estimate) -> Verdict:
    """Compare an estimate with the cell's bound.

    :param cell: The gate whose bound applies.
    :param estimate: The metric's value, CI and n.
    :returns: The :class:`Verdict`: passed, or why not.
    """
    b = cell.bound
    compared = {None: estimate.value, "lower": estimate.ci_low, "upper": estimate.ci_high}[b.ci]
    what = "value" if b.ci is None else f"CI {b.ci} end"
    if compared is None:
        passed = False
        reason = f"{what} undefined: {estimate.reason or 'no estimate'}"
    else:
        passed = compared >= b.value if b.kind == "min" else compared <= b.value
        op = (">=" if passed else "<") if b.kind == "min" else ("<=" if passed else ">")
        reason = f"{what} {compared:.4g} {op} {b.value:g}" + (
            "" if passed else _underpowered(b, estimate.value, compared, estimate.n)
        )
    if b.ci and estimate.value is not None and estimate.n == 1:
        reason += "; one episode has no CI: a CI bound needs at least 2 episodes in the cell"
    return Verdict(
        model=b.model,
        condition=b.condition,
        variant=cell.variant,
        metric=b.metric,
        kind=b.kind,
        bound=b.value,
        ci=b.ci,
        value=estimate.value,
        ci_low=estimate.ci_low,
        ci_high=estimate.ci_high,
        n=estimate.n,
        passed=passed,
        reason=reason,
        layouts=b.layouts,
    )


def _underpowered(b: Bound, value: float | None, compared: float, n: int) -> str:
    """When the point value passes and only the CI end fails: the cell's episodes are too few
    for the CI to clear the bound; about how many would at this spread (the CI half-width
    shrinks as 1/sqrt(n))."""
    if b.ci is None or value is None:
        return ""
    margin = value - b.value if b.kind == "min" else b.value - value
    if margin <= 0:
        return ""
    needed = math.ceil(n * ((value - compared) / margin) ** 2)
    return (
        f"; underpowered: the value {value:.4g} passes but {n} episode(s) give too wide a CI,"
        f" at this spread the bound needs about {needed} episodes in the cell"
        " (raise --emrd-episodes / EMRD_EPISODES, or gate the value without `ci`)"
    )


#: Per-episode values of the gate metrics that are not a per-episode field of their own.
_PER_EPISODE: Final[Mapping[str, Callable[[Any], float | None]]] = {
    "parse_failure_rate": lambda m: m.parse_failures / m.steps if m.steps else None,
    "errored_rate": lambda m: float(m.errored),
}
#: How many of a failed gate's worst episodes it lists.
WORST: Final = 5


def worst_episodes(
    verdict: Verdict, items: Iterable[Any], better: str, run_dir_of: Callable[[str], str]
) -> Verdict:
    """``verdict`` with its worst episodes and their ``emrd view`` command when it failed and
    the metric has per-episode values (``EpisodeMetrics``); ``run_dir_of`` maps a case id to
    the run directory holding it."""
    get = _PER_EPISODE.get(verdict.metric, lambda m: getattr(m, verdict.metric, None))
    values = [] if verdict.passed else [(m.spec.case_id, get(m)) for m in items]
    scored = [(case, float(v)) for case, v in values if isinstance(v, int | float)]
    if not scored:
        return verdict
    worst = tuple(sorted(scored, key=lambda cv: cv[1] if better == "higher" else -cv[1])[:WORST])
    by_dir: dict[str, list[str]] = defaultdict(list)
    for case, _ in worst:
        by_dir[run_dir_of(case)].append(case)
    view = " ; ".join(shlex.join(["emrd", "view", d, *cases]) for d, cases in by_dir.items())
    return replace(verdict, worst=worst, view=view)


def evaluate_cell(
    cell: GateCell,
    trajectories: Iterable[Any],
    metrics: Mapping[str, GateMetric],
    *,
    run_dir_of: Callable[[str], str] = lambda case: "RUN_DIR",
) -> Verdict:
    """The verdict of one gate over its episodes (any order in, sorted by case id): trajectories
    or anything with a ``spec`` the metric accepts (such as ``EpisodeMetrics``); a failed one
    names its worst episodes (:func:`worst_episodes`).

    :param cell: The gate and prompt variant.
    :param trajectories: The cell's episodes.
    :param metrics: Metric name -> :class:`GateMetric`.
    :param run_dir_of: Case id -> run directory, as for :func:`evaluate_all`.
    :returns: The cell's :class:`Verdict`.
    """
    ordered = sorted(trajectories, key=lambda t: t.spec.case_id)
    metric = metrics[cell.bound.metric]
    verdict = judge(cell, metric.compute(ordered, rng_seed=0))
    return worst_episodes(verdict, ordered, metric.better, run_dir_of)


def evaluate_all(
    trajectories: Iterable[Any],
    thresholds: Thresholds,
    metrics: Mapping[str, GateMetric],
    *,
    run_dir_of: Callable[[str], str] = lambda case: "RUN_DIR",
) -> list[Verdict]:
    """Every gate whose cell has episodes: the gate tests' verdicts, for ``emrd gate``.

    :param trajectories: Every episode of the run, any cell.
    :param thresholds: The gates.
    :param metrics: Metric name -> :class:`GateMetric` (:data:`GATE_METRICS`).
    :param run_dir_of: Case id -> the run directory its episode is in, for worst-episode links.
    :returns: One :class:`Verdict` per gate with episodes, in the file's order.
    """
    cells: dict[tuple[str, str, str, str], list[Any]] = defaultdict(list)
    for t in trajectories:
        cells[(t.spec.model, t.spec.condition, t.spec.variant, t.spec.layouts)].append(t)
    return [
        evaluate_cell(GateCell(bound, variant), episodes, metrics, run_dir_of=run_dir_of)
        for (model, condition, variant, layouts), episodes in sorted(cells.items())
        for bound in thresholds.for_cell(model, condition, layouts)
    ]
