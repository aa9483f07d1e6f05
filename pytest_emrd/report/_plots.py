"""The report's figures as PNG bytes (matplotlib, Agg canvas, no pyplot global state).

One colour per condition as in the paper and, so that coinciding series stay visible, one
line style, marker and hatch (:data:`CONDITION_STYLES`: the figures read in grey scale too),
markers staggered, the baseline on
top. One panel per model row. Titles are wrapped to their width, so no text leaves the canvas.
"""

from __future__ import annotations

import io
import math
import textwrap
from collections.abc import Callable, Sequence
from typing import Any, Final

import numpy as np
from matplotlib.artist import Artist
from matplotlib.axes import Axes
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.image import imsave
from matplotlib.lines import Line2D
from matplotlib.patches import Patch

from pytest_emrd._fork import pool
from pytest_emrd.report._model import CONDITION_NAMES, FIGURES, EpisodeMap, Report, rank
from pytest_emrd.rooms import ROOM_SLUGS, SLUG_ROOMS
from pytest_emrd.trajectory import CONDITIONS

CONDITION_STYLES: Final[dict[str, tuple[str, str, str, str]]] = {
    "baseline": ("#1f5fbf", "-", "o", ""),
    "low_light": ("#d62728", "--", "s", "//"),
    "texture": ("#2ca02c", "-.", "^", ".."),
}
_CATEGORY_MARKERS: Final[dict[str, str]] = {"landmark": "^", "salient": "s", "clutter": "o"}
_DPI: Final = 100
_OTHER_STYLE: Final = ("#7f7f7f", ":", "D", "xx")
#: Average glyph width of the default font, in units of its size (for wrapping titles).
_GLYPH: Final = 0.62
#: Y range of a share in [0, 1], with room for a line or marker at either end.
_SHARE_LIMITS: Final = (-0.02, 1.02)


def _style(condition: str) -> tuple[str, str, str, str]:
    return CONDITION_STYLES.get(condition, _OTHER_STYLE)


def colour(condition: str) -> str:
    return _style(condition)[0]


def line_style(condition: str, n_points: int = 0) -> dict[str, Any]:
    """Colour, line style, width and marker of ``condition``'s series; with ``n_points``, markers
    every ~n/8 points, staggered per condition so coinciding lines all show theirs. The
    baseline is drawn above the others with the smallest, filled markers."""
    hue, ls, marker, _ = _style(condition)
    place = rank(condition, CONDITIONS)[0]
    style: dict[str, Any] = {
        "color": hue,
        "ls": ls,
        "lw": 2,
        "marker": marker,
        "ms": 4.5 + 2.5 * place,
        "mfc": hue if place == 0 else "none",
        "mew": 1.5,
        "zorder": 3 - 0.1 * place,
    }
    if n_points:
        every = max(1, n_points // 8)
        style["markevery"] = ((place * max(1, every // 3)) % every, every)
    return style


def _wrap(text: str, width_in: float, size_pt: float) -> str:
    """``text`` broken into lines that fit ``width_in`` inches at ``size_pt`` points."""
    return textwrap.fill(text, max(12, int(width_in * 72 / (_GLYPH * size_pt))))


def _axes_title(ax: Axes, text: str) -> None:
    width = ax.get_position().width * ax.get_figure().get_figwidth()
    ax.set_title(_wrap(text, width, 10.0), fontsize=10)


def _panels(series: Sequence[Any]) -> tuple[Figure, dict[str, Axes]]:
    """One panel per model row of ``series``, three to a line."""
    labels = _labels(series)
    cols = min(3, len(labels))
    rows = math.ceil(len(labels) / cols)
    fig = Figure(figsize=(5.0 * cols, 3.6 * rows + 0.6), layout="constrained")
    axes = fig.subplots(rows, cols, squeeze=False).ravel()
    for ax in axes[len(labels) :]:
        ax.set_axis_off()
    return fig, dict(zip(labels, axes, strict=False))


def _png(fig: Figure) -> bytes:
    """The PNG ``fig.savefig(format="png", dpi=_DPI)`` writes, byte for byte, drawn once:
    ``savefig`` first draws the whole figure without rendering to run the layout engine,
    then draws it again (layout included) to render it."""
    fig.set_dpi(_DPI)
    canvas = FigureCanvasAgg(fig)
    canvas.draw()
    buffer = io.BytesIO()
    imsave(buffer, canvas.buffer_rgba(), format="png", origin="upper", dpi=_DPI)
    return buffer.getvalue()


def _finish(
    fig: Figure,
    axes: dict[str, Axes],
    title: str,
    conditions: Sequence[str],
    *,
    bars: bool = False,
    grid: str = "both",
    **axis: Any,
) -> Figure:
    """Every panel titled with its key, ``axis`` properties set and a grid; the figure's title
    and its legend of ``conditions`` (patches with ``bars``, else lines)."""
    for label, ax in axes.items():
        _axes_title(ax, label)
        ax.set(**axis)
        ax.grid(axis=grid, alpha=0.3)
    fig.suptitle(_wrap(title, fig.get_figwidth() - 0.2, 12.0), fontsize=12)
    handles: list[Artist] = [
        Patch(
            facecolor=colour(c),
            hatch=_style(c)[3],
            edgecolor="white",
            label=CONDITION_NAMES.get(c, c),
        )
        if bars
        else Line2D([], [], label=CONDITION_NAMES.get(c, c), **line_style(c))
        for c in conditions
    ]
    fig.legend(handles=handles, loc="outside lower center", ncols=len(handles), frameon=False)
    return fig


def _conditions(series: Sequence[Any]) -> list[str]:
    return list(dict.fromkeys(s.condition for s in series))


def _labels(items: Sequence[Any]) -> list[str]:
    return list(dict.fromkeys(i.label for i in items))


def _tbs(report: Report) -> Figure | None:
    series = [s for s in report.tbs if s.curve.n]
    if not series:
        return None
    fig, axes = _panels(series)
    for s in series:
        ax = axes[s.label]
        t, mean, sd = np.array(s.curve.t), np.array(s.curve.mean), np.array(s.curve.sd)
        ax.plot(t, mean, **line_style(s.condition, len(t)))
        ax.fill_between(t, mean - sd, mean + sd, color=colour(s.condition), alpha=0.12, lw=0)
    return _finish(
        fig,
        axes,
        "Temporal Belief Stability (mean ± 1 sd)",
        _conditions(series),
        xlabel="step t",
        ylabel="TBS(t) (0-1)",
        ylim=_SHARE_LIMITS,
    )


def _pa(report: Report) -> Figure | None:
    groups = [g for g in report.pa if g.values]
    if not groups:
        return None
    fig, axes = _panels(groups)
    conditions = _conditions(groups)
    spawns = [s for s in ROOM_SLUGS.values() if any(g.spawn == s for g in groups)]
    width = 0.8 / len(conditions)
    for g in groups:
        ax = axes[g.label]
        offset = conditions.index(g.condition) - (len(conditions) - 1) / 2
        x = spawns.index(g.spawn) + offset * width
        mean, sd = g.mean_sd
        hue, _, _, hatch = _style(g.condition)
        ax.bar(
            x,
            mean,
            width * 0.95,
            yerr=sd or 0.0,
            capsize=3,
            color=hue,
            alpha=0.85,
            hatch=hatch,
            edgecolor="white",
        )
    for ax in axes.values():
        ax.set_xticks(range(len(spawns)), [SLUG_ROOMS[s] for s in spawns])
    return _finish(
        fig,
        axes,
        "Positional Accuracy by spawn room and condition (mean ± 1 sd)",
        conditions,
        bars=True,
        grid="y",
        xlabel="spawn room",
        ylabel="Positional Accuracy (0-1)",
        ylim=(0, 1.05),
    )


def _miller(report: Report) -> Figure | None:
    series = [s for s in report.miller if s.curve.bins]
    if not series:
        return None
    fig, axes = _panels(series)
    width = series[0].curve.width
    for s in series:
        ax = axes[s.label]
        loads = np.array(s.curve.bins) * s.curve.width
        ax.plot(loads, s.curve.probabilities, **line_style(s.condition, len(loads)))
        if s.curve.m_star is not None:
            ax.axvline(s.curve.m_star, color=colour(s.condition), ls=":", lw=1.2)
    loads = [b * width for s in series for b in s.curve.bins]
    for ax in axes.values():  # a bin of margin each side, never an axis around one point
        ax.set_xlim(max(0, min(loads) - width), max(loads) + width)
    return _finish(
        fig,
        axes,
        "Miller's law: forgetting probability by cognitive load (dotted: m*)",
        _conditions(series),
        xlabel=f"map size m (objects, bin upper edge, w={width})",
        ylabel="P(forget >= 1 object)",
        ylim=_SHARE_LIMITS,
    )


def _km(report: Report) -> Figure | None:
    series = [s for s in report.km if s.km.n]
    if not series:
        return None
    labels = _labels(series)
    categories = list(dict.fromkeys(s.category for s in series))
    fig = Figure(figsize=(4.6 * len(categories), 3.4 * len(labels) + 0.6), layout="constrained")
    grid = fig.subplots(len(labels), len(categories), squeeze=False)
    panels = {
        f"{label}: {c}": ax
        for label, row in zip(labels, grid, strict=True)
        for c, ax in zip(categories, row, strict=True)
    }
    for s in series:
        km, hue = s.km, colour(s.condition)
        ax = panels[f"{s.label}: {s.category}"]
        ax.step(km.times, km.survival, where="post", **line_style(s.condition, len(km.times)))
        if km.ci_low:  # Greenwood 95 % band (lifelines), anchored like the curve
            ax.fill_between(
                km.times, km.ci_low, km.ci_high, step="post", lw=0, color=hue, alpha=0.15
            )
        efc = s.fit.efc
        if efc is not None and math.isfinite(efc):
            t = np.linspace(0, max(km.times), 100)
            ax.plot(t, km.coverage * np.exp(-t / efc), color=hue, ls=(0, (2, 2)), lw=1)
    title = "Coverage-anchored Kaplan-Meier survival, 95 % band (thin dashed: Ebbinghaus fit)"
    return _finish(
        fig,
        panels,
        title,
        _conditions(series),
        xlabel="steps out of view t",
        ylabel="S(t) (discovered & held)",
        ylim=_SHARE_LIMITS,
    )


def _sir(report: Report) -> Figure | None:
    series = [s for s in report.sir if s.sir.values]
    if not series:
        return None
    fig, axes = _panels(series)
    conditions = _conditions(series)
    for s in series:
        ax = axes[s.label]
        hue, _, marker, _ = _style(s.condition)
        pos = conditions.index(s.condition)
        values = np.array(s.sir.values)
        if len(values) > 1 and np.ptp(values) > 0:
            body = ax.violinplot(values, [pos], showmeans=True, widths=0.8)
            for part in body["bodies"]:
                part.set(facecolor=hue, edgecolor=hue, alpha=0.45)
            for key in ("cmeans", "cmins", "cmaxes", "cbars"):
                body[key].set(color=hue)
        jitter = np.linspace(-0.08, 0.08, len(values)) if len(values) > 1 else np.zeros(1)
        ax.scatter(pos + jitter, values, s=14, marker=marker, color=hue, alpha=0.6)
    for ax in axes.values():
        ax.set_xticks(range(len(conditions)), [CONDITION_NAMES.get(c, c) for c in conditions])
    return _finish(
        fig,
        axes,
        "Coverage-anchored Spatial Identity Resolution per episode",
        conditions,
        grid="y",
        xlabel="condition",
        ylabel="SIR (0-1)",
        ylim=_SHARE_LIMITS,
    )


def _episode_map(report: Report) -> Figure | None:
    m: EpisodeMap | None = report.episode_map
    if m is None:
        return None
    fig = Figure(figsize=(8.5, 7.5), layout="constrained")
    ax = fig.subplots()
    for room in m.rooms:
        poly = np.array([*room.polygon, room.polygon[0]])
        ax.fill(poly[:, 0], poly[:, 1], color="#f2f2f2", ec="#555555", lw=1.5, zorder=0)
        # the name sits inside the room's top edge, under every marker, on a white ground:
        # it never prints over an object, an entry or another room's name
        cx, top = poly[:-1, 0].mean(), poly[:-1, 1].max()
        ax.annotate(
            room.name,
            (cx, top),
            xytext=(0, -4),
            textcoords="offset points",
            ha="center",
            va="top",
            fontsize=9,
            color="#777777",
            zorder=1,
            bbox={"boxstyle": "round,pad=0.15", "fc": "white", "ec": "none", "alpha": 0.8},
        )
    truth = {o.object_id: o for o in m.objects}
    for category, marker in _CATEGORY_MARKERS.items():
        objs = [o for o in m.objects if o.category == category]
        if objs:
            ax.scatter(
                [o.x for o in objs],
                [o.z for o in objs],
                marker=marker,
                s=40,
                color="#333333",
                label=f"ground truth: {category}",
                zorder=3,
            )
    path = np.array(m.path)
    if len(path):
        ax.plot(path[:, 0], path[:, 1], color="#1f5fbf", lw=1.5, alpha=0.7, label="agent path")
        ax.scatter(*path[0], marker="*", s=220, color="#1f5fbf", zorder=4, label="spawn")
        ax.scatter(*path[-1], marker="X", s=120, color="#1f5fbf", zorder=4, label="last pose")
    for e in m.entries:
        if e.object_id in truth:
            o = truth[e.object_id]
            ax.plot([e.x, o.x], [e.z, o.z], color="#d62728", lw=0.8, alpha=0.6, zorder=2)
    for which, hue in (("matched", "#d62728"), ("unmatched", "#ff9900")):
        shown = [e for e in m.entries if (e.object_id is None) == (which == "unmatched")]
        if shown or which == "matched":  # the matched entries are in the legend even when none
            ax.scatter(
                [e.x for e in shown],
                [e.z for e in shown],
                marker="x",
                s=45,
                color=hue,
                label=f"cognitive map ({which})",
                zorder=5,
            )
    rmse = "n/a" if m.rmse is None else f"{m.rmse:.2f} m"
    _axes_title(
        ax, f"{m.case_id}: terminal map aligned (rotation {m.rotation_deg:.1f} deg, RMSE {rmse})"
    )
    ax.set(xlabel="x (m, spawn frame)", ylabel="z (m, spawn frame)")
    ax.set_aspect("equal")
    ax.grid(alpha=0.2)
    fig.legend(loc="outside lower center", ncols=4, frameon=False, fontsize=8)
    return fig


#: Figure file name -> how it is drawn and why it may not be, costliest to draw first (a
#: 240-episode run of one model): the order in which worker processes take them up.
_DRAW: Final[dict[str, tuple[Callable[[Report], Figure | None], str]]] = {
    "km.png": (_km, "no object category in the ground truth of a non-errored episode"),
    "episode_map.png": (_episode_map, "no episode ended with a non-empty cognitive map"),
    "pa_by_spawn.png": (_pa, "Positional Accuracy is undefined in every episode"),
    "sir.png": (_sir, "no episode re-entered a room with mapped objects"),
    "miller.png": (_miller, "no step with a non-empty cognitive map"),
    "tbs.png": (_tbs, "no non-errored episode with steps and |G_base| > 0"),
}


def draw(report: Report, name: str) -> Figure | None:
    """Figure ``name`` of the report; None when the report holds nothing to draw in it."""
    return _DRAW[name][0](report)


def _render(report: Report, name: str) -> bytes | None:
    return None if (fig := draw(report, name)) is None else _png(fig)


def render_figures(
    report: Report, *, processes: int = 1
) -> tuple[dict[str, bytes], dict[str, str]]:
    """PNG bytes per figure file name (in :data:`FIGURES` order), and for each figure not
    drawn, why not. ``processes`` > 1 draws them in that many forked workers where forking is
    safe, each taking up the next (costliest first): the same code, the same bytes."""
    workers = pool(processes)
    if workers is not None:
        with workers:
            done = dict(zip(_DRAW, workers.map(_render, [report] * len(_DRAW), _DRAW), strict=True))
    else:
        done = {name: _render(report, name) for name in _DRAW}
    drawn = {f.name: png for f in FIGURES if (png := done[f.name]) is not None}
    return drawn, {f.name: _DRAW[f.name][1] for f in FIGURES if f.name not in drawn}
