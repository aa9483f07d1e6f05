"""Build a :class:`Report` from episodes and verdicts: grouping, every table and figure, what
is missing (pure: reading run directories and writing files is the caller's job)."""

from __future__ import annotations

from collections import Counter
from collections.abc import Mapping, Sequence

from pytest_emrd import metrics
from pytest_emrd._fork import beside
from pytest_emrd.gate import UsageRow, Verdict
from pytest_emrd.metrics import EpisodeMetrics
from pytest_emrd.report._model import (
    EbbinghausRow,
    ExplorationRow,
    FocalTable,
    FPSGRow,
    Gates,
    MillerSeries,
    Overview,
    Reasoning,
    Report,
    SerialRow,
    SIRSeries,
    TBSSeries,
    rank,
    row_label,
)
from pytest_emrd.report._tables import (
    Cells,
    Embed,
    anova_rows,
    episode_map,
    intervention_tables,
    km_series,
    pa_by_spawn,
    per_cell,
    pick_episode,
    reasoning,
    sd_of,
)
from pytest_emrd.rooms import ROOM_SLUGS
from pytest_emrd.run import EpisodeHead, StoredEpisode
from pytest_emrd.trajectory import CONDITIONS, VARIANTS, EpisodeSpec, Trajectory

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
    case-id order within a cell."""
    cells: dict[tuple[str, str, str], list[EpisodeMetrics]] = {}
    for m in sorted(measured, key=lambda m: m.spec.case_id):
        cells.setdefault((cell_model(m.spec), m.spec.variant, m.spec.condition), []).append(m)
    order = sorted(cells, key=lambda k: (k[0], rank(k[1], VARIANTS), rank(k[2], CONDITIONS)))
    return {k: cells[k] for k in order}


def _usage(heads: Sequence[EpisodeHead], prices: Prices | None) -> tuple[UsageRow, ...]:
    rows = []
    for model in sorted({h.spec.model for h in heads}):
        mine = [h for h in heads if h.spec.model == model]
        prompt = sum(h.usage.prompt_tokens for h in mine)
        completion = sum(h.usage.completion_tokens for h in mine)
        price_in, price_out = (prices or {}).get(model, (None, None))
        cost = None
        if price_in is not None and price_out is not None:
            cost = (prompt * price_in + completion * price_out) / 1e6
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
    heads: Sequence[EpisodeHead],
    overview: Overview,
    gates: Gates,
    reasons: Reasoning,
    stored: Sequence[StoredEpisode],
) -> tuple[str, ...]:
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
    in a forked worker while the tables are computed (same result)."""
    stored = [e if isinstance(e, StoredEpisode) else _wrap(e) for e in episodes]
    heads = [e.head for e in stored]
    overview = _overview(heads, prices)
    gates = Gates(thresholds_source, tuple(verdicts or ()))
    cells: Cells = group_cells(
        metrics.as_episode_metrics(
            [e.trajectory for e in stored] if episode_metrics is None else episode_metrics
        )
    )
    by_label: dict[str, list[EpisodeMetrics]] = {}
    for (model, variant, _), ems in cells.items():
        by_label.setdefault(row_label(model, variant), []).extend(ems)
    chosen = pick_episode(stored, episode)
    fork = processes > 1 and chosen is not None
    if fork:  # the alignment and lifelines both use it: imported once, before the fork
        import scipy.optimize  # noqa: F401
    with beside(episode_map, chosen, fork=fork) as mapped:
        reasons = reasoning(by_label, embed) if with_reasoning else Reasoning(())
        ebbinghaus = per_cell(cells, EbbinghausRow, metrics.ebbinghaus)
        aec, te = metrics.GATE_METRICS["aec"], metrics.GATE_METRICS["te"]
        return Report(
            overview=overview,
            missing=_missing(heads, overview, gates, reasons, stored),
            exploration=per_cell(
                cells, ExplorationRow, aec.compute, sd_of("aec"), te.compute, sd_of("te")
            ),
            focal=per_cell(cells, FocalTable, metrics.focal_distribution, metrics.consensus),
            fpsg=per_cell(cells, FPSGRow, metrics.fpsg),
            ebbinghaus=ebbinghaus,
            serial_position=per_cell(cells, SerialRow, metrics.serial_position),
            anova=anova_rows(cells),
            interventions=intervention_tables(cells),
            reasoning=reasons,
            gates=gates,
            tbs=per_cell(cells, TBSSeries, metrics.tbs_curve),
            pa=pa_by_spawn(cells),
            miller=per_cell(cells, MillerSeries, metrics.miller_curve),
            km=km_series(cells, {(r.model, r.variant, r.condition): r.fit for r in ebbinghaus}),
            sir=per_cell(cells, SIRSeries, metrics.spatial_identity_resolution),
            episode_map=mapped(),
        )


def _wrap(trajectory: Trajectory) -> StoredEpisode:
    """A trajectory handed in directly, as a stored episode (its head computed from it)."""
    return StoredEpisode.of(trajectory, session="", recorded=False, frame_drift=0, seconds=0.0)
