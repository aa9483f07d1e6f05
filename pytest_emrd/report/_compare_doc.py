"""Lay a :class:`Comparison` out as a document: one table per cell (pure)."""

from __future__ import annotations

from pytest_emrd.metrics import GATE_METRICS
from pytest_emrd.report._compare import Comparison, Difference
from pytest_emrd.report._document import (
    Block,
    Bullets,
    Cell,
    Document,
    Paragraph,
    Section,
    Table,
    num,
    pval,
)
from pytest_emrd.report._model import row_label
from pytest_emrd.report._style import CONDITION_NAMES

_HEADER = ("Metric", "Better", "A", "B", "B - A", "95% CI", "p (Holm)", "Verdict", "Note")


def _row(d: Difference) -> tuple[Cell, ...]:
    note = d.reason or ""
    if d.unpaired:
        note = f"{d.unpaired} unpaired episode(s) left out. {note}".strip()
    return (
        Cell(d.metric),
        Cell(GATE_METRICS[d.metric].better),
        Cell(f"{num(d.a.value)} (n={d.a.n})"),
        Cell(f"{num(d.b.value)} (n={d.b.n})"),
        Cell(num(d.diff)),
        Cell("n/a" if d.ci_low is None else f"[{num(d.ci_low)}, {num(d.ci_high)}]"),
        Cell(pval(d.p_holm)),
        Cell(d.verdict, bold=d.verdict in ("better", "worse", "inconclusive")),
        Cell(note),
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
        blocks.append(Bullets(tuple(notes)))
    if not c.differences:
        blocks.append(Paragraph("The two sides share no model x prompt x condition cell."))
    cells = list(dict.fromkeys((d.model, d.model_b, d.variant, d.condition)
                               for d in c.differences))  # fmt: skip
    for model, model_b, variant, condition in cells:
        rows = tuple(
            _row(d) for d in c.differences if (d.model, d.model_b, d.variant, d.condition)
            == (model, model_b, variant, condition)
        )  # fmt: skip
        who = model if model == model_b else f"{model} vs {model_b}"
        label = f"{row_label(who, variant)}, {CONDITION_NAMES.get(condition, condition)}"
        blocks.append(Table(f"compare-{model}-{model_b}-{variant}-{condition}", label, _HEADER,
                            rows))  # fmt: skip
    return Document("EMRD comparison", (Section("compare", "Differences", tuple(blocks)),))
