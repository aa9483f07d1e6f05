"""Every report figure: no text outside the canvas, coinciding series still distinguishable."""

from __future__ import annotations

import dataclasses

import pytest
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.text import Text

from pytest_emrd.report import FIGURES, build_report
from pytest_emrd.report._plots import draw
from pytest_emrd.trajectory import Trajectory


def _rename(ts: list[Trajectory], model: str, variant: str = "default") -> list[Trajectory]:
    return [dataclasses.replace(t, spec=dataclasses.replace(t.spec, model=model, variant=variant))
            for t in ts]  # fmt: skip


@pytest.fixture(scope="module")
def figures(variant_grid: list[Trajectory]) -> dict[str, Figure]:
    """One panel and many panels with long labels: every figure of both reports."""
    one = build_report(_rename(variant_grid[:24], "scout"), with_reasoning=False)
    many = build_report(
        variant_grid + _rename(variant_grid[:24], "scout-decay-8-with-a-long-name", "no_inventory"),
        with_reasoning=False,
    )
    drawn = {f"{which}/{f.name}": draw(report, f.name)
             for which, report in (("one", one), ("many", many)) for f in FIGURES}  # fmt: skip
    return {name: fig for name, fig in drawn.items() if fig is not None}


def test_every_figure_is_drawn(figures: dict[str, Figure]) -> None:
    assert set(figures) == {f"{r}/{f.name}" for r in ("one", "many") for f in FIGURES}


def _undrawn_tick_labels(fig: Figure) -> set[int]:
    """Tick labels matplotlib keeps but does not draw (ticks outside the view limits)."""
    hidden: set[int] = set()
    for ax in fig.axes:
        for axis in (ax.xaxis, ax.yaxis):
            low, high = sorted(axis.get_view_interval())
            for tick in axis.get_major_ticks() + axis.get_minor_ticks():
                if not low - 1e-9 <= tick.get_loc() <= high + 1e-9:
                    hidden |= {id(tick.label1), id(tick.label2)}
    return hidden


def test_no_text_leaves_the_canvas(figures: dict[str, Figure]) -> None:
    outside = []
    for name, fig in figures.items():
        FigureCanvasAgg(fig)
        renderer = fig.canvas.get_renderer()
        fig.draw(renderer)
        width, height = fig.bbox.width, fig.bbox.height
        hidden = _undrawn_tick_labels(fig)
        texts = [t for t in fig.findobj(Text)
                 if t.get_visible() and t.get_text().strip() and id(t) not in hidden]  # fmt: skip
        assert texts, name
        for t in texts:
            box = t.get_window_extent(renderer)
            if box.x0 < -0.5 or box.y0 < -0.5 or box.x1 > width + 0.5 or box.y1 > height + 0.5:
                outside.append((name, t.get_text(), tuple(round(v) for v in box.extents)))
    assert not outside, outside


@pytest.mark.parametrize("name", ["tbs.png", "miller.png", "km.png"])
def test_condition_lines_differ_in_style_and_marker(figures, name: str) -> None:
    """Baseline, low light and texture lines never share colour, line style and marker, and
    the baseline is drawn on top (the texture line cannot hide it)."""
    ax = figures[f"one/{name}"].axes[0]
    lines = [ln for ln in ax.get_lines() if ln.get_marker() not in ("None", None, "")]
    by_colour: dict[str, Line2D] = {ln.get_color(): ln for ln in lines}
    assert len(by_colour) == 3
    styles = {(ln.get_linestyle(), ln.get_marker()) for ln in by_colour.values()}
    assert len(styles) == 3
    base = by_colour["#1f5fbf"]
    assert base.get_zorder() > max(ln.get_zorder() for ln in lines if ln is not base)


def test_pa_bars_carry_a_hatch_per_condition(figures) -> None:
    ax = figures["one/pa_by_spawn.png"].axes[0]
    hatches = {(p.get_facecolor()[:3], p.get_hatch()) for p in ax.patches}
    assert len({h for _, h in hatches}) == 3


def test_room_names_on_the_episode_map_print_over_nothing(figures) -> None:
    """Each room's name lies inside its room, clear of every other name and of every marker
    (objects, map entries, the path's ends)."""
    import numpy as np
    from matplotlib.collections import PathCollection

    for key in ("one/episode_map.png", "many/episode_map.png"):
        fig = figures[key]
        FigureCanvasAgg(fig)
        renderer = fig.canvas.get_renderer()
        fig.draw(renderer)
        ax = fig.axes[0]
        names = [t for t in ax.texts if t.get_text().strip()]
        boxes = [t.get_window_extent(renderer) for t in names]
        assert len(boxes) >= 4, key
        for i, a in enumerate(boxes):
            for b in boxes[i + 1 :]:
                assert not a.overlaps(b), (key, names[boxes.index(a)].get_text())
        offsets = [c.get_offsets() for c in ax.collections if isinstance(c, PathCollection)]
        points = np.concatenate([ax.transData.transform(o) for o in offsets])
        for text, box in zip(names, boxes, strict=True):
            inside = [p for p in points if box.x0 < p[0] < box.x1 and box.y0 < p[1] < box.y1]
            assert not inside, (key, text.get_text(), inside)


@pytest.mark.parametrize("name", ["tbs.png", "miller.png", "km.png", "sir.png"])
def test_no_curve_lies_on_an_axis(figures, name: str) -> None:
    """A share of 0 or 1 stays visible: every plotted y lies strictly inside the view."""
    import numpy as np

    for key in (f"one/{name}", f"many/{name}"):
        for ax in figures[key].axes:
            low, high = ax.get_ylim()
            for line in ax.get_lines():
                y = np.asarray(line.get_ydata(), float)
                y = y[np.isfinite(y)]
                if y.size and line.get_visible():
                    assert low < y.min() and y.max() < high, (key, line.get_label(), low, high)


def test_tbs_is_drawn_to_the_last_step_an_episode_reached(grid: list[Trajectory]) -> None:
    quit_early = [dataclasses.replace(t, steps=t.steps[:4]) for t in grid[:8]]
    (series,) = [s for s in build_report(quit_early, with_reasoning=False).tbs if s.curve.n]
    assert series.curve.t == (1, 2, 3, 4)


def test_miller_axis_keeps_a_bin_each_side_of_one_point(grid: list[Trajectory]) -> None:
    report = build_report(grid[:8], with_reasoning=False)
    series = report.miller[0]
    c = series.curve
    one = dataclasses.replace(
        c,
        bins=c.bins[:1],
        probabilities=c.probabilities[:1],
        steps=c.steps[:1],
        events=c.events[:1],
        b_star=None,
        m_star=None,
    )
    one_bin = dataclasses.replace(report, miller=(dataclasses.replace(series, curve=one),))
    low, high = draw(one_bin, "miller.png").axes[0].get_xlim()
    assert high - low >= 2 * c.width
