"""Lay a :class:`Report` out as the paper's tables: a format-neutral :class:`Document` (pure)."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any, Final

from pytest_emrd.metrics import FocalRow
from pytest_emrd.report._document import (
    Block,
    Bullets,
    Cell,
    Document,
    FigureRef,
    Paragraph,
    Row,
    Section,
    Table,
    mean_sd,
    num,
    pct,
    pval,
)
from pytest_emrd.report._model import (
    CONDITION_NAMES,
    FIGURES,
    CellRow,
    InterventionTable,
    Report,
    row_label,
)
from pytest_emrd.rooms import FOCAL_COLUMNS, ROOM_LETTERS, SLUG_ROOMS, room_letter

_LETTER_ROOMS = {letter: room for room, letter in ROOM_LETTERS.items()} | {"X": "Other"}


def _cond(condition: str) -> str:
    """The paper's name and the key thresholds.yaml and ``--emrd-condition`` use:
    ``Light & Vis. (low_light)``; a name that is its key is printed once."""
    name = CONDITION_NAMES.get(condition, condition)
    return name if name.lower() == condition else f"{name} ({condition})"


#: How to start gating, where no gate ran for want of a thresholds file.
START_GATES: Final = (
    "Start one from this run: `emrd thresholds RUN_DIR --out thresholds.yaml` "
    "(docs/user-guide/ci.md)."
)
#: Below this R² the exponential explains less of the KM curve than its own mean does.
R2_MEANINGLESS: Final = 0.0


def _pivot(
    report: Report,
    rows: Sequence[CellRow],
    names: Sequence[str],
    fmt: Callable[[Any], Sequence[str]],
) -> tuple[tuple[str, ...], list[Row]]:
    """Header and lines of a table with one line per model row and, per condition of the run,
    a column per name (``fmt`` of the row's cell gives them; blank where it has no cell)."""
    conditions = report.overview.conditions
    table: dict[str, dict[str, Sequence[str]]] = {}
    for r in rows:
        table.setdefault(r.label, {})[r.condition] = fmt(r)
    blank = ("—",) * len(names)
    header = ("Model", *(f"{n} {_cond(c)}" for c in conditions for n in names))
    return header, [
        (label, *(t for c in conditions for t in by_c.get(c, blank)))
        for label, by_c in table.items()
    ]


def overview(report: Report) -> Section:
    o = report.overview
    status = ", ".join(f"{k} {v}" for k, v in o.by_status.items()) or "none"
    blocks: list[Block] = [
        Paragraph(
            f"{o.episodes} episodes ({status}); models: {', '.join(o.models) or '—'}; "
            f"conditions: {', '.join(map(_cond, o.conditions)) or '—'}; "
            f"prompt variants: {', '.join(o.variants) or '—'}; "
            f"spawn rooms: {', '.join(SLUG_ROOMS.get(s, s) for s in o.spawns) or '—'}"
        )
    ]
    if o.usage:
        rows = [u.cells() for u in o.usage]
        header = ("Model", "Episodes", "Prompt tokens", "Completion tokens", "Est. cost")
        blocks.append(Table("usage", "Token usage per model", header, rows))
        unpriced = [u.model for u in o.usage if u.cost_usd is None]
        if unpriced:
            blocks.append(
                Paragraph(
                    f"Est. cost n/a for {', '.join(unpriced)}: the registry this report read "
                    "has no price for it (a self-hosted model; or a model of your own registry: "
                    "pass `--models FILE` to `emrd report`, as to the run)."
                )
            )
    if report.missing:
        blocks.append(Paragraph("**What this run is missing:**"))
        blocks.append(Bullets(report.missing))
    return Section("overview", "Run overview", blocks)


def gates(report: Report) -> Section:
    g = report.gates
    if not g.verdicts:
        started = f"No thresholds file was given or found, so no gate ran. {START_GATES}"
        why = g.note or (f"No gate of {g.source} applies to this run." if g.source else started)
        return Section("gates", "Gates", (Paragraph(why),))
    passed = sum(v.passed for v in g.verdicts)
    rows = [
        (
            v.model if v.layouts == "paper" else f"{v.model}@{v.layouts}",
            _cond(v.condition),
            v.variant,
            v.metric,
            num(v.value),
            f"[{num(v.ci_low)}, {num(v.ci_high)}]",
            str(v.n),
            v.bound_text,
            Cell("PASS" if v.passed else "FAIL", bold=not v.passed),
            v.reason,
        )
        for v in g.verdicts
    ]
    header = (
        "Model",
        "Condition",
        "Prompt",
        "Metric",
        "Value",
        "95% CI",
        "n",
        "Bound",
        "Result",
        "Why",
    )
    return Section(
        "gates",
        "Gates",
        (
            Paragraph(
                f"{passed}/{len(g.verdicts)} gates pass ({g.source}). Values, CIs and bounds "
                "are in the units of the thresholds file: rates and shares as fractions "
                "(0.9), which the tables below print as percentages (90.0)."
            ),
            Table(
                "gates", "Every threshold: value, bootstrap 95% CI, n, bound, verdict", header, rows
            ),
            *(
                Bullets([f"{v.gate_id}: {e}" for e in v.evidence()])
                for v in g.verdicts
                if v.evidence()
            ),
        ),
    )


def exploration(report: Report) -> Section:
    header, rows = _pivot(
        report,
        report.exploration,
        ("AEC (%)", "TE (steps)"),
        lambda r: (
            f"{mean_sd(r.aec.value, r.aec_sd, scale=100)} (n={r.aec.n})",
            f"{mean_sd(r.te.value, r.te_sd)} (n={r.te.n})",
        ),
    )
    caption = "Exploration Competence: AEC (%) and TE (actions), mean ± sd (Eq. AEC, TE)"
    return Section(
        "exploration",
        "Exploration Competence",
        (Table("exploration", caption, header, rows),),
    )


def positional_accuracy(report: Report) -> Section:
    """PA (Eq. PA) per spawn room and condition: the numbers behind pa_by_spawn.png."""
    rows = [
        (
            g.label,
            _cond(g.condition),
            SLUG_ROOMS.get(g.spawn, g.spawn),
            f"{mean_sd(*g.mean_sd, digits=3)} (n={len(g.values)})",
        )
        for g in report.pa
    ]
    if not rows:
        text = "Positional Accuracy is undefined in every episode (|G_base| = 0)."
        return Section("pa", "Positional Accuracy", (Paragraph(text),))
    header = ("Model", "Condition", "Spawn room", "PA (0-1), mean ± sd")
    caption = (
        "Positional Accuracy per spawn room (Eq. PA; episodes where it is defined), "
        "the figure pa_by_spawn.png in numbers"
    )
    return Section("pa", "Positional Accuracy", (Table("pa", caption, header, rows),))


def _spawn_order(item: tuple[str, FocalRow]) -> int:
    """The paper's row order of start rooms: C, O, K, E."""
    return FOCAL_COLUMNS.index(room_letter(SLUG_ROOMS.get(item[0])))


_FOCAL_HEADER: Final = (
    "Condition",
    "Start",
    "n",
    *FOCAL_COLUMNS,
    "X: other room",
    "X: no Term",
    "Spawn room (%)",
    "Consensus",
)


def focal(report: Report) -> Section:
    """One table per model row: the chosen rooms by spawn room, then over all spawns."""
    by_label: dict[str, list[Row]] = {}
    for t in report.focal:
        most = t.consensus
        share = "n/a" if most.share is None else f"{most.letter or '—'} {pct(most.share)}%"
        spawns = sorted(t.distribution.by_spawn.items(), key=_spawn_order)
        for start, row, consensus in (
            *((SLUG_ROOMS.get(spawn, spawn), row, "") for spawn, row in spawns),
            (Cell("all spawns", bold=True), t.distribution.overall, share),
        ):
            shares = (Cell(pct(f), shade=f) for f in map(row.fractions.get, FOCAL_COLUMNS))
            by_label.setdefault(t.label, []).append(
                (
                    _cond(t.condition),
                    start,
                    str(row.n),
                    *shares,
                    str(row.named_other),
                    str(row.no_term),
                    pct(row.spawn_share),
                    consensus,
                )
            )
    tables = [
        Table(
            f"focal-{label}",
            f"{label}: chosen focal point (%) by spawn room — C Conference, O Office, "
            "K Kitchen, E Entrance, X other: counted apart as a Term naming another "
            "room and no Term (budget spent); Spawn room: the share that chose the room "
            "they started in (Appendix F: 50.6 %, chance 25 %)",
            _FOCAL_HEADER,
            rows,
        )
        for label, rows in by_label.items()
    ]
    return Section("focal", "Focal-Point distribution", tables)


def fpsg(report: Report) -> Section:
    rows = [
        (
            _cond(r.condition),
            r.label,
            str(s.runs),
            pct(s.never_visited),
            pct(s.any_bias),
            mean_sd(s.local_mean, s.local_sd, digits=3),
            mean_sd(s.global_mean, s.global_sd, digits=3),
        )
        for r in report.fpsg
        for s in (r.summary,)
    ]
    header = (
        "Condition",
        "Model",
        "Runs",
        "Never Visited (%)",
        "Any Bias (%)",
        "FPSG local",
        "FPSG global",
    )
    caption = "Focal-Point Spatial Grounding (Eq. FSPG), mean ± sd"
    return Section("fpsg", "Focal-Point Spatial Grounding", (Table("fpsg", caption, header, rows),))


def ebbinghaus(report: Report) -> Section:
    efc_header, efc = _pivot(
        report, report.ebbinghaus, ["EFC"], lambda r: [num(r.fit.pooled.efc, 1)]
    )
    r2_header, r2 = _pivot(report, report.ebbinghaus, ["R²"], lambda r: [num(r.fit.pooled.r2, 2)])
    header = (*efc_header, *r2_header[1:])  # the EFC columns, then the R² ones
    rows = [(*a, *b[1:]) for a, b in zip(efc, r2, strict=True)]
    caption = (
        "Ebbinghaus memory strength EFC (steps; inf: nothing forgotten) and R² of "
        "C exp(-t/EFC) against the anchored KM"
    )
    blocks: list[Block] = [Table("ebbinghaus", caption, header, rows)]
    poor = sorted(
        f"{r.label}, {_cond(r.condition)} (R² {num(r.fit.pooled.r2, 2)})"
        for r in report.ebbinghaus
        if r.fit.pooled.r2 is not None and r.fit.pooled.r2 < R2_MEANINGLESS
    )
    if poor:
        blocks.append(
            Paragraph(
                "**R² below 0 means the exponential fits the KM curve worse than a flat line at "
                "its mean: the EFC of these cells describes no forgetting curve and is not to be "
                f"compared:** {'; '.join(poor)}."
            )
        )
    if report.anova:
        anova_rows = [
            (
                row_label(a.model, a.variant),
                num(a.anova.statistic, 2),
                f"{a.anova.df_between:g}, {a.anova.df_within:g}",
                pval(a.anova.p_value),
                ", ".join(f"{_cond(c)} {n}" for c, n in a.anova.groups.items()) or "—",
                a.anova.reason or "",
            )
            for a in report.anova
        ]
        header = ("Model", "F", "df", "p", "Episodes used", "Note")
        caption = "One-way ANOVA of per-episode memory strength across conditions"
        blocks.append(Table("anova", caption, header, anova_rows))
    return Section("ebbinghaus", "Ebbinghaus memory strength", blocks)


def serial_position(report: Report) -> Section:
    """Both estimators: the paper's Eq. SPE and the censoring-aware MLE per third."""

    def thirds(*fields: str) -> tuple[tuple[str, ...], list[Row]]:
        return _pivot(
            report,
            report.serial_position,
            ("E", "M", "L"),
            lambda r: [num(getattr(r.spe, f), 1) for f in fields],
        )

    header, paper = thirds("early", "middle", "late")
    _, mle = thirds("mle_early", "mle_middle", "mle_late")
    caption = (
        "Serial Position Effect (paper's Eq. SPE): mean observed TTF (steps) of Early / "
        "Middle / Late discoveries, episode-end censoring ignored"
    )
    caption_mle = (
        "Serial Position Effect, censoring-aware: Σ durations / forgetting events "
        "(steps) per third, the MLE of Eq. SMLE; inf: nothing of that third was "
        "forgotten"
    )
    return Section(
        "serial-position",
        "Serial Position Effect",
        (
            Table("serial-position", caption, header, paper),
            Table("serial-position-mle", caption_mle, header, mle),
        ),
    )


def _intervention(t: InterventionTable) -> list[Block]:
    def shares(row: FocalRow) -> Row:
        f = row.fractions
        other = None if not row.n else 1.0 - f["C"] - f["E"]
        return (str(row.n), pct(f["C"]), pct(f["E"]), pct(other))

    rows = [("default", *shares(t.reference), *("—",) * 4)]
    for v in t.variants:
        chi = v.chi_square
        rows.append(
            (
                v.variant,
                *shares(v.choices),
                pval(v.fisher.p_value) if v.fisher else "n/a",
                f"{num(chi.statistic, 2)} ({chi.dof})",
                pval(chi.p_value),
                num(v.cramers_v, 2),
            )
        )
    header = (
        "Prompt",
        "n",
        "Conf. (%)",
        "Entr. (%)",
        "Other (%)",
        "p (Fisher, Conf. vs other)",
        "χ² (df), C/O/K/E/X",
        "p (χ²)",
        "Cramér's V",
    )
    caption = f"{t.model}, {_cond(t.condition)}: prompt variants against the default prompt"
    blocks: list[Block] = [Table(f"intervention-{t.model}-{t.condition}", caption, header, rows)]
    if t.overall is not None:
        o = t.overall
        text = (
            f"Overall ({', '.join(t.overall_variants)}; Conference vs other): "
            f"χ² = {num(o.statistic, 2)}, df = {o.dof}, p = {pval(o.p_value)}"
            + (f" ({o.reason})" if o.reason else "")
        )
        blocks.append(Paragraph(text))
    inventory = next((v for v in t.variants if v.variant == "no_inventory"), None)
    if inventory is not None:
        with_, without = t.reference, inventory.choices
        inv_rows = [
            (
                _LETTER_ROOMS[c],
                str(with_.counts[c]),
                pct(with_.fractions[c]),
                str(without.counts[c]),
                pct(without.fractions[c]),
            )
            for c in ("C", "K", "E", "O", "X")
        ]
        header = ("Chosen room", "n with inventory", "% with", "n without inventory", "% without")
        caption = f"{t.model}, {_cond(t.condition)}: inventory-free intervention"
        blocks.append(Table(f"inventory-{t.model}-{t.condition}", caption, header, inv_rows))
    return blocks


def interventions(report: Report) -> Section:
    if not report.interventions:
        why = (
            "No model and condition holds both the default prompt and a prompt variant, so "
            "there is no intervention to test."
        )
        return Section("interventions", "Controlled interventions", (Paragraph(why),))
    blocks = [b for t in report.interventions for b in _intervention(t)]
    return Section("interventions", "Controlled interventions", blocks)


def reasoning(report: Report) -> Section:
    r = report.reasoning
    if r.unavailable:
        return Section("reasoning", "Representative reasoning", (Paragraph(r.unavailable),))
    rows = [
        (
            x.model,
            num(x.representative.mean_cosine_distance, 2),
            f"{x.representative.n} ({x.representative.skipped} without)",
            x.representative.statement or "no terminal reasoning",
        )
        for x in r.rows
    ]
    header = ("Model", "d̄ (cohesion)", "Rationales", "Most representative terminal reasoning")
    caption = "Statement closest to the semantic centroid (all-MiniLM-L6-v2)"
    return Section(
        "reasoning", "Representative reasoning", (Table("reasoning", caption, header, rows),)
    )


def figures(report: Report, skipped: dict[str, str]) -> Section:
    """Every figure; the episode map's caption names its episode (``emrd report --episode``)."""
    shown = report.episode_map and report.episode_map.case_id
    named = f" Episode {shown} (choose another with --episode CASE_ID)." if shown else ""
    refs = [
        FigureRef(
            f.name,
            f.title,
            f.caption + (named if f.name == "episode_map.png" else ""),
            skipped.get(f.name),
        )
        for f in FIGURES
    ]
    return Section("figures", "Figures", refs)


def report_document(report: Report, skipped: dict[str, str]) -> Document:
    """The full report: overview, gates, every table, every figure."""
    return Document(
        "EMRD report",
        (
            overview(report),
            gates(report),
            exploration(report),
            positional_accuracy(report),
            focal(report),
            fpsg(report),
            ebbinghaus(report),
            serial_position(report),
            interventions(report),
            reasoning(report),
            figures(report, skipped),
        ),
    )


def summary_document(report: Report) -> Document:
    """The short form for PR comments and ``$GITHUB_STEP_SUMMARY``: no figures."""
    return Document(
        "EMRD results",
        (
            overview(report),
            gates(report),
            exploration(report),
            fpsg(report),
        ),
    )
