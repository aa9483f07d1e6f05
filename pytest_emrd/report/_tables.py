"""The paper's tables, computed from grouped episode metrics (pure).

Each function calls the metrics library and wraps its results in report rows; the only
arithmetic done here is the sample standard deviation shown next to a mean (``mean +- sd``).
"""

from __future__ import annotations

import statistics
from collections.abc import Callable, Mapping, Sequence

import numpy as np

from pytest_emrd.errors import MissingExtraError
from pytest_emrd.metrics import (
    GATE_METRICS,
    EpisodeMetrics,
    anova_conditions,
    chi_square,
    consensus,
    cramers_v,
    ebbinghaus,
    fisher_exact_2x2,
    focal_distribution,
    fpsg,
    representative_reasoning,
    serial_position,
)
from pytest_emrd.report._model import (
    AnovaRow,
    EbbinghausRow,
    ExplorationRow,
    FocalTable,
    FPSGRow,
    InterventionTable,
    Reasoning,
    ReasoningRow,
    SerialRow,
    VariantTest,
)
from pytest_emrd.rooms import FOCAL_COLUMNS, ROOM_LETTERS
from pytest_emrd.trajectory import VARIANTS

#: (model, variant, condition) -> that cell's episode metrics, in case-id order.
Cells = Mapping[tuple[str, str, str], Sequence[EpisodeMetrics]]
Embed = Callable[[Sequence[str]], np.ndarray]

#: Letter of the paper's intervention outcome (Conference Room vs any other choice).
_CONFERENCE = ROOM_LETTERS["Conference Room"]
#: Variants of the paper's overall chi-square (B1-B4 vs the default prompt).
_BODY_VARIANTS = ("B1", "B2", "B3", "B4")


def _sd(values: Sequence[float | int | None]) -> float | None:
    clean = [float(v) for v in values if v is not None]
    return statistics.stdev(clean) if len(clean) >= 2 else None


def exploration_rows(cells: Cells) -> tuple[ExplorationRow, ...]:
    """AEC and TE (mean, bootstrap CI, sd) per cell: ``GATE_METRICS['aec'|'te']``."""
    return tuple(
        ExplorationRow(
            model,
            variant,
            condition,
            GATE_METRICS["aec"].compute(ems),
            _sd([m.aec for m in ems if not m.errored]),
            GATE_METRICS["te"].compute(ems),
            _sd([m.te for m in ems if not m.errored]),
        )
        for (model, variant, condition), ems in cells.items()
    )


def focal_tables(cells: Cells) -> tuple[FocalTable, ...]:
    return tuple(
        FocalTable(m, v, c, focal_distribution(ems), consensus(ems))
        for (m, v, c), ems in cells.items()
    )


def fpsg_rows(cells: Cells) -> tuple[FPSGRow, ...]:
    return tuple(FPSGRow(m, v, c, fpsg(ems)) for (m, v, c), ems in cells.items())


def ebbinghaus_rows(cells: Cells) -> tuple[EbbinghausRow, ...]:
    return tuple(EbbinghausRow(m, v, c, ebbinghaus(ems)) for (m, v, c), ems in cells.items())


def serial_rows(cells: Cells) -> tuple[SerialRow, ...]:
    return tuple(SerialRow(m, v, c, serial_position(ems)) for (m, v, c), ems in cells.items())


def anova_rows(cells: Cells) -> tuple[AnovaRow, ...]:
    """ANOVA across the conditions of each model x variant (all its cells pooled)."""
    pooled: dict[tuple[str, str], list[EpisodeMetrics]] = {}
    for (model, variant, _), ems in cells.items():
        pooled.setdefault((model, variant), []).extend(ems)
    return tuple(AnovaRow(m, v, anova_conditions(ems)) for (m, v), ems in pooled.items())


def _conference_split(counts: Mapping[str, int]) -> list[int]:
    chose = counts.get(_CONFERENCE, 0)
    return [chose, sum(counts.values()) - chose]


def intervention_tables(cells: Cells) -> tuple[InterventionTable, ...]:
    """Prompt variants vs the default prompt, per model x condition holding both.

    Per variant: two-sided Fisher exact test on Conference vs other choices, Pearson
    chi-square and Cramer's V on the C/O/K/E/X distribution. Overall: Pearson chi-square of
    Conference vs other across the default prompt and the B1-B4 variants present (the paper's
    5 x 2 table). Errored episodes are excluded, as in every focal-point count.
    """
    by_cell: dict[tuple[str, str], dict[str, Sequence[EpisodeMetrics]]] = {}
    for (model, variant, condition), ems in cells.items():
        by_cell.setdefault((model, condition), {})[variant] = ems
    tables = []
    for (model, condition), variants in by_cell.items():
        if "default" not in variants or len(variants) < 2:
            continue
        reference = focal_distribution(variants["default"]).overall
        ref_counts = [reference.counts[c] for c in FOCAL_COLUMNS]
        tests = []
        for variant in sorted((v for v in variants if v != "default"), key=_variant_order):
            row = focal_distribution(variants[variant]).overall
            table = [ref_counts, [row.counts[c] for c in FOCAL_COLUMNS]]
            split = [_conference_split(reference.counts), _conference_split(row.counts)]
            fisher = fisher_exact_2x2(split) if reference.n and row.n else None
            tests.append(VariantTest(variant, row, fisher, chi_square(table), cramers_v(table)))
        body = [t for t in tests if t.variant in _BODY_VARIANTS]
        overall = None
        if body:
            rows = [_conference_split(reference.counts)]
            rows += [_conference_split(t.choices.counts) for t in body]
            overall = chi_square(rows)
        names = ("default", *(t.variant for t in body)) if body else ()
        tables.append(InterventionTable(model, condition, reference, tuple(tests), overall, names))
    return tuple(tables)


def _variant_order(variant: str) -> tuple[int, str]:
    return (VARIANTS.index(variant) if variant in VARIANTS else len(VARIANTS), variant)


def reasoning(by_label: Mapping[str, Sequence[EpisodeMetrics]], embed: Embed | None) -> Reasoning:
    """Representative terminal reasoning per model row (all its conditions pooled, as the
    paper); without the ``nlp`` extra, why not."""
    unique = _unique(embed)
    rows = []
    for label, ems in by_label.items():
        rationales = [m.rationale for m in ems if not m.errored]
        try:
            rows.append(ReasoningRow(label, representative_reasoning(rationales, embed=unique)))
        except MissingExtraError as exc:
            return Reasoning((), str(exc))
    return Reasoning(tuple(rows))


def _unique(embed: Embed | None) -> Embed:
    """``embed`` (default: the ``nlp`` extra's encoder) evaluated once per distinct text.

    Identical rationales get identical vectors either way; scripted agents repeat theirs, so
    this saves most of the encoder's time without changing the result.
    """

    def run(texts: Sequence[str]) -> np.ndarray:
        encoder = embed
        if encoder is None:
            from pytest_emrd.metrics._embedding import minilm_embed

            encoder = minilm_embed
        distinct = list(dict.fromkeys(texts))
        where = {t: i for i, t in enumerate(distinct)}
        vectors = np.asarray(encoder(distinct), dtype=float)
        if vectors.ndim != 2 or len(vectors) != len(distinct):
            return vectors  # malformed: representative_reasoning reports the shape
        return vectors[[where[t] for t in texts]]

    return run
