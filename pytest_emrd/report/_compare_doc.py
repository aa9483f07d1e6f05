"""Lay a :class:`Comparison` out as a document: one table per cell (pure)."""

from __future__ import annotations

from pytest_emrd.report._compare import Comparison
from pytest_emrd.report._document import (
    Block,
    Bullets,
    Cell,
    Document,
    Paragraph,
    Section,
    Table,
    num,
)
from pytest_emrd.report._model import row_label
from pytest_emrd.report._style import CONDITION_NAMES


def compare_document(c: Comparison) -> Document:
    """Per cell: metric, value in A and B (n), B - A, its 95 % CI and significance."""
    blocks: list[Block] = [
        Paragraph(
            f"A = {c.run_a}, B = {c.run_b}. Differences are B - A with a seeded (rng_seed="
            f"{c.rng_seed}) two-sample percentile bootstrap 95% CI over episodes "
            f"({c.n_resamples} resamples); **yes** marks a CI that excludes 0."
        )
    ]
    if c.only_a or c.only_b:
        notes = [f"only in A (not compared): {k}" for k in c.only_a]
        notes += [f"only in B (not compared): {k}" for k in c.only_b]
        blocks.append(Bullets(tuple(notes)))
    if not c.differences:
        blocks.append(Paragraph("The two runs share no model x prompt x condition cell."))
    cells = list(dict.fromkeys((d.model, d.variant, d.condition) for d in c.differences))
    for model, variant, condition in cells:
        rows = tuple(
            (Cell(d.metric), Cell(f"{num(d.a.value)} (n={d.a.n})"),
             Cell(f"{num(d.b.value)} (n={d.b.n})"), Cell(num(d.diff)),
             Cell("n/a" if d.ci_low is None else f"[{num(d.ci_low)}, {num(d.ci_high)}]"),
             Cell({None: "n/a", True: "yes", False: "no"}[d.significant],
                  bold=bool(d.significant)),
             Cell(d.reason or ""))
            for d in c.differences
            if (d.model, d.variant, d.condition) == (model, variant, condition)
        )  # fmt: skip
        label = f"{row_label(model, variant)}, {CONDITION_NAMES.get(condition, condition)}"
        header = ("Metric", "A", "B", "B - A", "95% CI", "Significant", "Note")
        blocks.append(Table(f"compare-{model}-{variant}-{condition}", label, header, rows))
    return Document("EMRD run comparison", (Section("compare", "Differences", tuple(blocks)),))
