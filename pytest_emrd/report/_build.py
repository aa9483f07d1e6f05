"""Build a :class:`Report` from episodes and verdicts: grouping, every table and figure, what
is missing (pure: reading run directories and writing files is the caller's job). The numbers
are the metrics library's results in report rows; computed here are only the sample sd shown
next to a mean and the rigid alignment of the map figure."""

from __future__ import annotations

import math
import statistics
from collections import Counter
from collections.abc import Callable, Mapping, Sequence
from typing import Any

import numpy as np

from pytest_emrd import metrics
from pytest_emrd._fork import beside
from pytest_emrd.errors import ConfigError, MissingExtraError
from pytest_emrd.gate import UsageRow, Verdict
from pytest_emrd.metrics import EpisodeMetrics
from pytest_emrd.report._model import (
    AnovaRow,
    EbbinghausRow,
    EpisodeMap,
    ExplorationRow,
    FocalTable,
    FPSGRow,
    Gates,
    InterventionTable,
    KMSeries,
    MapPoint,
    MillerSeries,
    Overview,
    PASpawn,
    Reasoning,
    ReasoningRow,
    Report,
    SerialRow,
    SIRSeries,
    TBSSeries,
    VariantTest,
    rank,
    row_label,
)
from pytest_emrd.rooms import FOCAL_COLUMNS, ROOM_LETTERS, ROOM_SLUGS
from pytest_emrd.run import EpisodeHead, StoredEpisode
from pytest_emrd.trajectory import CONDITIONS, VARIANTS, EpisodeSpec, MapEntry, Trajectory

#: (model, variant, condition) -> that cell's episode metrics, in case-id order.
Cells = Mapping[tuple[str, str, str], Sequence[EpisodeMetrics]]
Embed = Callable[[Sequence[str]], np.ndarray]

#: Letter of the paper's intervention outcome (Conference Room vs any other choice).
_CONFERENCE = ROOM_LETTERS["Conference Room"]
#: Variants of the paper's overall chi-square (B1-B4 vs the default prompt).
_BODY_VARIANTS = ("B1", "B2", "B3", "B4")


def per_cell(
    cells: Mapping[tuple[str, ...], Sequence[EpisodeMetrics]],
    row: Callable[..., Any],
    *compute: Callable[[Any], Any],
) -> tuple:
    """``row(*key, *(f(episodes) for f in compute))`` for every cell (key: model, variant,
    condition) or model row (:func:`model_rows`, key: model, variant)."""
    return tuple(row(*key, *(f(ems) for f in compute)) for key, ems in cells.items())


def sd_of(field: str) -> Callable[[Sequence[EpisodeMetrics]], float | None]:
    """The sample standard deviation of a per-episode metric over a cell's non-errored
    episodes where it is defined (None with fewer than two values)."""

    def sd(ems: Sequence[EpisodeMetrics]) -> float | None:
        values = [float(v) for m in ems if not m.errored and (v := getattr(m, field)) is not None]
        return statistics.stdev(values) if len(values) >= 2 else None

    return sd


def model_rows(cells: Cells) -> dict[tuple[str, str], list[EpisodeMetrics]]:
    """The episodes of each model x variant, its cells (conditions) pooled."""
    pooled: dict[tuple[str, str], list[EpisodeMetrics]] = {}
    for (model, variant, _), ems in cells.items():
        pooled.setdefault((model, variant), []).extend(ems)
    return pooled


def _conference_split(row: metrics.FocalRow) -> list[int]:
    chose = row.counts.get(_CONFERENCE, 0)
    return [chose, sum(row.counts.values()) - chose]


def intervention_tables(focal: Sequence[FocalTable]) -> tuple[InterventionTable, ...]:
    """Prompt variants vs the default prompt, per model x condition holding both, from the
    cells' focal-point tables.

    Per variant: two-sided Fisher exact test on Conference vs other choices, Pearson
    chi-square and Cramer's V on the C/O/K/E/X distribution. Overall: Pearson chi-square of
    Conference vs other across the default prompt and the B1-B4 variants present (the paper's
    5 x 2 table). Errored episodes are excluded, as in every focal-point count.
    """
    by_cell: dict[tuple[str, str], dict[str, metrics.FocalRow]] = {}
    for t in focal:  # variants in the paper's order
        by_cell.setdefault((t.model, t.condition), {})[t.variant] = t.distribution.overall
    tables = []
    for (model, condition), variants in by_cell.items():
        if "default" not in variants or len(variants) < 2:
            continue
        reference = variants.pop("default")
        tests = []
        for variant, row in variants.items():
            table = [[r.counts[c] for c in FOCAL_COLUMNS] for r in (reference, row)]
            split = [_conference_split(reference), _conference_split(row)]
            fisher = metrics.fisher_exact_2x2(split) if reference.n and row.n else None
            chi = metrics.chi_square(table)
            tests.append(VariantTest(variant, row, fisher, chi, metrics.cramers_v(table)))
        body = [t for t in tests if t.variant in _BODY_VARIANTS]
        splits = [_conference_split(r) for r in (reference, *(t.choices for t in body))]
        overall = metrics.chi_square(splits) if body else None
        names = ("default", *(t.variant for t in body)) if body else ()
        tables.append(InterventionTable(model, condition, reference, tuple(tests), overall, names))
    return tuple(tables)


def reasoning(
    pooled: Mapping[tuple[str, str], Sequence[EpisodeMetrics]], embed: Embed | None
) -> Reasoning:
    """Representative terminal reasoning per model row (all its conditions pooled, as the
    paper); without the ``nlp`` extra, why not."""
    rows = []
    for (model, variant), ems in pooled.items():
        rationales = [m.rationale for m in ems if not m.errored]
        try:
            rep = metrics.representative_reasoning(rationales, embed=_unique(embed))
        except MissingExtraError as exc:
            return Reasoning((), str(exc))
        rows.append(ReasoningRow(row_label(model, variant), rep))
    return Reasoning(tuple(rows))


def _unique(embed: Embed | None) -> Embed:
    """``embed`` (default: the ``nlp`` extra's encoder) evaluated once per distinct text: the
    same vectors, and scripted agents repeat their rationales, so most of the encoder's time."""

    def run(texts: Sequence[str]) -> np.ndarray:
        from pytest_emrd.metrics import minilm_embed

        encoder = embed or minilm_embed
        distinct = list(dict.fromkeys(texts))
        where = {t: i for i, t in enumerate(distinct)}
        vectors = np.asarray(encoder(distinct), dtype=float)
        if vectors.ndim != 2 or len(vectors) != len(distinct):
            return vectors  # malformed: representative_reasoning reports the shape
        return vectors[[where[t] for t in texts]]

    return run


def pa_by_spawn(cells: Cells) -> tuple[PASpawn, ...]:
    """Per-episode Positional Accuracy grouped by spawn room (``positional_accuracy``)."""
    return tuple(
        PASpawn(*key, spawn, tuple(m.pa for m in ems if m.spec.spawn == spawn and m.pa is not None))
        for key, ems in cells.items()
        for spawn in dict.fromkeys(m.spec.spawn for m in ems)
    )


def km_series(cells: Cells, ebbinghaus: Sequence[EbbinghausRow]) -> tuple[KMSeries, ...]:
    """Anchored KM per category with the Ebbinghaus fit of the same category (``ebbinghaus``:
    the cells' rows in cell order, computed once for their table)."""
    return tuple(
        KMSeries(*key, category, km, row.fit.by_category[category])
        for (key, ems), row in zip(cells.items(), ebbinghaus, strict=True)
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
        found = [e for e in episodes if e.head.spec.case_id == case_id]
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
    rotation in degrees and the RMS residual of the pairs (None without pairs).

    :param entries: The map as written.
    :param matching: Its matching to ground truth.
    :returns: ``(points, rotation_deg, rms)``.
    """
    matched = {p.label: p.object_id for p in matching.pairs}
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
            points[e.label] = MapPoint(e.label, float(x), float(z), matched.get(e.label))
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


#: Model name -> USD per million (prompt, completion) tokens, for the usage table.
Prices = Mapping[str, tuple[float | None, float | None]]


def _ordered(values: set[str], order: Sequence[str]) -> tuple[str, ...]:
    return tuple(sorted(values, key=lambda v: rank(v, order)))


def cell_model(spec: EpisodeSpec) -> str:
    """The model label of a report cell: the model, ``@generated`` appended under generated
    layouts (``scout@generated``), so paper-protocol and generated-layout episodes are never
    aggregated together and every table shows which protocol a row comes from."""
    return spec.model if spec.layouts == "paper" else f"{spec.model}@{spec.layouts}"


def group_cells(
    measured: Sequence[EpisodeMetrics],
) -> dict[tuple[str, str, str], list[EpisodeMetrics]]:
    """Episodes by (model, variant, condition): models sorted (:func:`cell_model`, so generated
    layouts form cells of their own), variants and conditions in the paper's order, episodes in
    case-id order within a cell.

    :param measured: The episodes' metrics.
    :returns: ``(model, variant, condition)`` -> its episodes, in the order above.
    """
    cells: dict[tuple[str, str, str], list[EpisodeMetrics]] = {}
    for m in sorted(measured, key=lambda m: m.spec.case_id):
        cells.setdefault((cell_model(m.spec), m.spec.variant, m.spec.condition), []).append(m)
    order = sorted(cells, key=lambda k: (k[0], rank(k[1], VARIANTS), rank(k[2], CONDITIONS)))
    return {k: cells[k] for k in order}


def _usage(heads: Sequence[EpisodeHead], prices: Prices | None) -> tuple[UsageRow, ...]:
    rows = []
    for model in sorted({h.spec.model for h in heads}):
        mine = [h.usage for h in heads if h.spec.model == model]
        prompt = sum(u.prompt_tokens for u in mine)
        completion = sum(u.completion_tokens for u in mine)
        price_in, price_out = (prices or {}).get(model, (None, None))
        priced = price_in is not None and price_out is not None
        cost = (prompt * price_in + completion * price_out) / 1e6 if priced else None
        rows.append(UsageRow(model, len(mine), prompt, completion, cost))
    return tuple(rows)


def _overview(heads: Sequence[EpisodeHead], prices: Prices | None) -> Overview:
    specs = [h.spec for h in heads]
    return Overview(
        episodes=len(heads),
        by_status=dict(sorted(Counter(h.status for h in heads).items())),
        models=tuple(sorted({s.model for s in specs})),
        conditions=_ordered({s.condition for s in specs}, CONDITIONS),
        variants=_ordered({s.variant for s in specs}, VARIANTS),
        spawns=_ordered({s.spawn for s in specs}, tuple(ROOM_SLUGS.values())),
        usage=_usage(heads, prices),
    )


def _missing(
    stored: Sequence[StoredEpisode], overview: Overview, gates: Gates, reasons: Reasoning
) -> tuple[str, ...]:
    heads = [e.head for e in stored]
    if not heads:
        return (
            "The run holds no episode, so there is nothing to tabulate or plot: run "
            "`pytest benchmarks --emrd-results DIR` and pass DIR to `emrd report`.",
        )
    notes = []
    errored = [h for h in heads if h.status == "errored"]
    if errored:
        causes = Counter((h.error or "no cause recorded").splitlines()[0][:120] for h in errored)
        top = "; ".join(f"{c} (x{n})" for c, n in causes.most_common(3))
        if len(errored) == len(heads):
            notes.append(
                f"All {len(errored)} episodes errored, so every metric is undefined "
                f"(causes: {top}). Fix the cause and rerun the run directory."
            )
        else:
            notes.append(
                f"{len(errored)} of {len(heads)} episodes errored and are excluded "
                f"from every table and figure (causes: {top})."
            )
    absent = [c for c in CONDITIONS if c not in overview.conditions]
    if absent:
        notes.append(
            f"No episode ran under condition(s) {', '.join(absent)}: their columns are empty "
            "and the one-way ANOVA needs at least two conditions "
            "(run with --emrd-condition baseline,low_light,texture)."
        )
    variants = overview.variants
    if variants == ("default",):
        notes.append(
            "Only the default prompt was run: the controlled-intervention tables need prompt "
            "variants (B1-B4, neutral, no_inventory) of the same model and condition."
        )
    elif "default" not in variants:
        notes.append(
            f"Prompt variant(s) {', '.join(variants)} ran without the default prompt: the "
            "intervention tests compare each variant with default episodes of the same cell."
        )
    if gates.source is None:
        notes.append(
            "No thresholds file was given or found: the gate section is empty "
            "(pass --thresholds thresholds.yaml)."
        )
    elif not gates.verdicts:
        notes.append(f"No gate of {gates.source} applies to the models and conditions run.")
    if reasons.unavailable:
        notes.append(f"Representative reasoning is not computed: {reasons.unavailable}")
    if pick_episode(stored) is None:
        notes.append("No episode ended with a non-empty cognitive map: no map figure is drawn.")
    return tuple(notes)


def build_report(
    episodes: Sequence[Trajectory | StoredEpisode],
    *,
    verdicts: Sequence[Verdict] | None = None,
    thresholds_source: str | None = None,
    embed: Embed | None = None,
    prices: Prices | None = None,
    with_reasoning: bool = True,
    episode_metrics: Sequence[EpisodeMetrics] | None = None,
    episode: str | None = None,
    processes: int = 1,
) -> Report:
    """Every table and figure of the paper for ``episodes`` (errored ones excluded and
    reported); with ``episode_metrics`` (their metrics, measured already) only the map
    figure's episode is decoded. ``verdicts``: the gate verdicts of the file
    ``thresholds_source``; ``embed`` replaces the ``nlp`` extra's sentence encoder;
    ``prices`` adds estimated cost to the usage table; ``with_reasoning=False`` leaves the
    reasoning table empty (no encoder loaded); ``episode``: the case id the map figure shows
    (default: the first baseline episode with a map); ``processes`` > 1 aligns that episode
    in a forked worker while the tables are computed (same result).

    :param episodes: Trajectories or stored episodes of one or several runs.
    :param verdicts: The gate verdicts, or None for no gate table.
    :param thresholds_source: The thresholds file the verdicts come from.
    :param embed: Texts -> embeddings; None for the ``nlp`` extra's encoder.
    :param prices: Model -> USD per million input and output tokens.
    :param with_reasoning: Build the reasoning table (loads the encoder).
    :param episode_metrics: The episodes' metrics, in ``episodes`` order, if measured already.
    :param episode: Case id of the map figure's episode.
    :param processes: Processes that align the map figure's steps.
    :returns: The :class:`Report`.
    """
    stored = [  # a trajectory handed in directly: its head is computed from it
        e
        if isinstance(e, StoredEpisode)
        else StoredEpisode.of(e, session="", recorded=False, frame_drift=0, seconds=0.0)
        for e in episodes
    ]
    heads = [e.head for e in stored]
    overview = _overview(heads, prices)
    gates = Gates(thresholds_source, tuple(verdicts or ()))
    measured = [e.trajectory for e in stored] if episode_metrics is None else episode_metrics
    cells: Cells = group_cells(metrics.as_episode_metrics(measured))
    pooled = model_rows(cells)
    chosen = pick_episode(stored, episode)
    fork = processes > 1 and chosen is not None
    if fork:  # the alignment and lifelines both use it: imported once, before the fork
        import scipy.optimize  # noqa: F401
    with beside(episode_map, chosen, fork=fork) as mapped:
        reasons = reasoning(pooled, embed) if with_reasoning else Reasoning(())
        ebbinghaus = per_cell(cells, EbbinghausRow, metrics.ebbinghaus)
        focal = per_cell(cells, FocalTable, metrics.focal_distribution, metrics.consensus)
        aec, te = metrics.GATE_METRICS["aec"], metrics.GATE_METRICS["te"]
        return Report(
            overview=overview,
            missing=_missing(stored, overview, gates, reasons),
            exploration=per_cell(
                cells, ExplorationRow, aec.compute, sd_of("aec"), te.compute, sd_of("te")
            ),
            focal=focal,
            fpsg=per_cell(cells, FPSGRow, metrics.fpsg),
            ebbinghaus=ebbinghaus,
            serial_position=per_cell(cells, SerialRow, metrics.serial_position),
            anova=per_cell(pooled, AnovaRow, metrics.anova_conditions),
            interventions=intervention_tables(focal),
            reasoning=reasons,
            gates=gates,
            tbs=per_cell(cells, TBSSeries, _tbs_to_last_step),
            pa=pa_by_spawn(cells),
            miller=per_cell(cells, MillerSeries, metrics.miller_curve),
            km=km_series(cells, ebbinghaus),
            sir=per_cell(cells, SIRSeries, metrics.spatial_identity_resolution),
            episode_map=mapped(),
        )


def _tbs_to_last_step(ems: Sequence[EpisodeMetrics]) -> metrics.TBSCurve:
    """The cell's TBS curve up to the last step its longest episode reached (not the budget:
    a cell whose episodes all ended at step 4 is drawn to step 4)."""
    return metrics.tbs_curve(ems, t_max=max((len(m.tbs) for m in ems), default=0))
