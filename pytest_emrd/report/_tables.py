"""The data of the paper's tables and figures, from grouped episode metrics (pure): the
metrics library's results in report rows; computed here are only the sample sd shown next to
a mean and the rigid alignment of the map figure."""

from __future__ import annotations

import math
import statistics
from collections.abc import Callable, Mapping, Sequence
from typing import Any

import numpy as np

from pytest_emrd import metrics
from pytest_emrd.errors import ConfigError, MissingExtraError
from pytest_emrd.metrics import EpisodeMetrics
from pytest_emrd.report._model import (
    AnovaRow,
    EpisodeMap,
    InterventionTable,
    KMSeries,
    MapPoint,
    PASpawn,
    Reasoning,
    ReasoningRow,
    VariantTest,
    rank,
)
from pytest_emrd.rooms import FOCAL_COLUMNS, ROOM_LETTERS
from pytest_emrd.run import StoredEpisode
from pytest_emrd.trajectory import VARIANTS, MapEntry

#: (model, variant, condition) -> that cell's episode metrics, in case-id order.
Cells = Mapping[tuple[str, str, str], Sequence[EpisodeMetrics]]
Embed = Callable[[Sequence[str]], np.ndarray]

#: Letter of the paper's intervention outcome (Conference Room vs any other choice).
_CONFERENCE = ROOM_LETTERS["Conference Room"]
#: Variants of the paper's overall chi-square (B1-B4 vs the default prompt).
_BODY_VARIANTS = ("B1", "B2", "B3", "B4")


def per_cell(cells: Cells, row: Callable[..., Any], *compute: Callable[[Any], Any]) -> tuple:
    """``row(model, variant, condition, *(f(episodes) for f in compute))`` for every cell."""
    return tuple(row(*key, *(f(ems) for f in compute)) for key, ems in cells.items())


def sd_of(field: str) -> Callable[[Sequence[EpisodeMetrics]], float | None]:
    """The sample standard deviation of a per-episode metric over a cell's non-errored
    episodes where it is defined (None with fewer than two values)."""

    def sd(ems: Sequence[EpisodeMetrics]) -> float | None:
        values = [float(v) for m in ems if not m.errored and (v := getattr(m, field)) is not None]
        return statistics.stdev(values) if len(values) >= 2 else None

    return sd


def anova_rows(cells: Cells) -> tuple[AnovaRow, ...]:
    """ANOVA across the conditions of each model x variant (all its cells pooled)."""
    pooled: dict[tuple[str, str], list[EpisodeMetrics]] = {}
    for (model, variant, _), ems in cells.items():
        pooled.setdefault((model, variant), []).extend(ems)
    return tuple(AnovaRow(*k, metrics.anova_conditions(ems)) for k, ems in pooled.items())


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
        reference = metrics.focal_distribution(variants["default"]).overall
        ref_counts = [reference.counts[c] for c in FOCAL_COLUMNS]
        tests = []
        for variant in sorted(
            (v for v in variants if v != "default"), key=lambda v: rank(v, VARIANTS)
        ):
            row = metrics.focal_distribution(variants[variant]).overall
            table = [ref_counts, [row.counts[c] for c in FOCAL_COLUMNS]]
            split = [_conference_split(reference.counts), _conference_split(row.counts)]
            fisher = metrics.fisher_exact_2x2(split) if reference.n and row.n else None
            chi, v = metrics.chi_square(table), metrics.cramers_v(table)
            tests.append(VariantTest(variant, row, fisher, chi, v))
        body = [t for t in tests if t.variant in _BODY_VARIANTS]
        overall = None
        if body:
            rows = [_conference_split(reference.counts)]
            rows += [_conference_split(t.choices.counts) for t in body]
            overall = metrics.chi_square(rows)
        names = ("default", *(t.variant for t in body)) if body else ()
        tables.append(InterventionTable(model, condition, reference, tuple(tests), overall, names))
    return tuple(tables)


def reasoning(by_label: Mapping[str, Sequence[EpisodeMetrics]], embed: Embed | None) -> Reasoning:
    """Representative terminal reasoning per model row (all its conditions pooled, as the
    paper); without the ``nlp`` extra, why not."""
    unique = _unique(embed)
    rows = []
    for label, ems in by_label.items():
        rationales = [m.rationale for m in ems if not m.errored]
        try:
            rep = metrics.representative_reasoning(rationales, embed=unique)
        except MissingExtraError as exc:
            return Reasoning((), str(exc))
        rows.append(ReasoningRow(label, rep))
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


def pa_by_spawn(cells: Cells) -> tuple[PASpawn, ...]:
    """Per-episode Positional Accuracy grouped by spawn room (``positional_accuracy``)."""
    out = []
    for key, ems in cells.items():
        by_spawn: dict[str, list[EpisodeMetrics]] = {}
        for m in ems:
            by_spawn.setdefault(m.spec.spawn, []).append(m)
        for spawn, group in by_spawn.items():
            values = tuple(v for v in metrics.positional_accuracy(group) if v is not None)
            out.append(PASpawn(*key, spawn, values))
    return tuple(out)


def km_series(cells: Cells, fits: Mapping[tuple[str, str, str], Any]) -> tuple[KMSeries, ...]:
    """Anchored KM per category with the Ebbinghaus fit of the same category (``fits``: the
    cells' :func:`~pytest_emrd.metrics.ebbinghaus`, computed once for their table)."""
    return tuple(
        KMSeries(*key, category, km, fits[key].by_category[category])
        for key, ems in cells.items()
        for category, km in metrics.kaplan_meier_anchored(ems).items()
    )


def pick_episode(
    episodes: Sequence[StoredEpisode], case_id: str | None = None
) -> StoredEpisode | None:
    """The episode the map figure shows: ``case_id`` when given (a :class:`ConfigError` naming
    a few of the run's case ids when the run has no such episode), else the first non-errored
    one (baseline first, case-id order) whose terminal map holds an entry; None when there is
    none. Chosen from the episodes' heads: no trajectory is decoded."""
    heads = [e.head for e in episodes]
    if case_id is not None:
        found = [e for e, h in zip(episodes, heads, strict=True) if h.spec.case_id == case_id]
        if not found:
            held = sorted(h.spec.case_id for h in heads)
            shown = ", ".join(held[:3]) + (", ..." if len(held) > 3 else "")
            raise ConfigError(
                f"episode={case_id!r} is not in the run ({len(held)} episodes: {shown}); "
                "pass a case id as the test ids show it, e.g. scout-baseline-office-ep00."
            )
        return found[0]
    candidates = [
        (h.spec.condition != "baseline", h.spec.case_id, i)
        for i, h in enumerate(heads)
        if h.status != "errored" and h.final_map_entries
    ]
    return episodes[min(candidates)[2]] if candidates else None


def align_map(
    entries: Sequence[MapEntry], matching: metrics.Matching
) -> tuple[tuple[MapPoint, ...], float, float | None]:
    """A cognitive map moved by :func:`rigid_fit` of its matched pairs onto the ground truth
    (unmatched entries move with it; a repeated label is shown once): the points, the fit's
    rotation in degrees and the RMS residual of the pairs (None without pairs)."""
    matched = {p.label: p for p in matching.pairs}
    rot, shift = np.eye(2), np.zeros(2)
    rmse = None
    if matching.pairs:
        pred = np.array([(p.pred_x, p.pred_z) for p in matching.pairs])
        true = np.array([(p.true_x, p.true_z) for p in matching.pairs])
        rot, shift = metrics.rigid_fit(pred, true)
        rmse = float(np.sqrt(np.mean(np.sum((pred @ rot.T + shift - true) ** 2, axis=1))))
    points = {}
    for e in entries:
        if e.label not in points:
            x, z = np.array([e.x, e.z]) @ rot.T + shift
            pair = matched.get(e.label)
            points[e.label] = MapPoint(
                e.label, float(x), float(z), pair.object_id if pair else None
            )
    return tuple(points.values()), math.degrees(math.atan2(rot[1, 0], rot[0, 0])), rmse


def episode_map(chosen: StoredEpisode | None) -> EpisodeMap | None:
    """Ground truth, path and the terminal map of ``chosen`` (its trajectory decoded here)
    aligned by :func:`align_map` on the pairs of :func:`match_map`; None without an episode."""
    if chosen is None:
        return None
    traj = chosen.trajectory
    truth = traj.ground_truth
    matching = metrics.match_map(traj.final_map, truth.objects)
    points, rotation, rmse = align_map(traj.final_map, matching)
    path = tuple((s.pose.x, s.pose.z) for s in traj.steps)
    return EpisodeMap(traj.spec.case_id, truth.rooms, truth.objects, path, points, rotation, rmse)
