"""Gate verdicts: a metric's estimate over a cell's episodes (model x condition x prompt
variant x layouts), compared with its bound (pure). Episodes are sorted by case id and the
bootstrap is seeded (``rng_seed=0``): the same episodes give the same verdict anywhere."""

from __future__ import annotations

from collections import defaultdict
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

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
    """Compare an estimate with the cell's bound."""
    b = cell.bound
    compared = {None: estimate.value, "lower": estimate.ci_low, "upper": estimate.ci_high}[b.ci]
    what = "value" if b.ci is None else f"CI {b.ci} end"
    if compared is None:
        passed = False
        reason = f"{what} undefined: {estimate.reason or 'no estimate'}"
    else:
        passed = compared >= b.value if b.kind == "min" else compared <= b.value
        op = (">=" if passed else "<") if b.kind == "min" else ("<=" if passed else ">")
        reason = f"{what} {compared:.4g} {op} {b.value:g}"
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


def evaluate_cell(
    cell: GateCell, trajectories: Iterable[Any], metrics: Mapping[str, GateMetric]
) -> Verdict:
    """The verdict of one gate over its episodes (any order in, sorted by case id): trajectories
    or anything with a ``spec`` the metric accepts (such as ``EpisodeMetrics``)."""
    ordered = sorted(trajectories, key=lambda t: t.spec.case_id)
    return judge(cell, metrics[cell.bound.metric].compute(ordered, rng_seed=0))


def evaluate_all(
    trajectories: Iterable[Any], thresholds: Thresholds, metrics: Mapping[str, GateMetric]
) -> list[Verdict]:
    """Every gate whose cell has episodes: the gate tests' verdicts, for ``emrd gate``."""
    cells: dict[tuple[str, str, str, str], list[Any]] = defaultdict(list)
    for t in trajectories:
        cells[(t.spec.model, t.spec.condition, t.spec.variant, t.spec.layouts)].append(t)
    return [
        evaluate_cell(GateCell(bound, variant), episodes, metrics)
        for (model, condition, variant, layouts), episodes in sorted(cells.items())
        for bound in thresholds.for_cell(model, condition, layouts)
    ]
