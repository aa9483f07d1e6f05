"""Reports: the paper's tables and figures from any run.

Compute (pure): :func:`build_report` (a :class:`Report` of the metrics library's results),
:func:`compare_runs`. Render (pure): :func:`render_files` (Markdown + PNG, self-contained
HTML, JSON), :func:`render_comparison`, :func:`step_summary_markdown`. Write (I/O):
:func:`write_report`, :func:`write_files`.

Typical use::

    trajectories = pytest_emrd.run.load_run_dirs([Path("results/run1")])
    write_report(build_report(trajectories), Path("results/run1/report"))
"""

from __future__ import annotations

import dataclasses
import json
import os
from collections.abc import Iterable, Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Final

from pytest_emrd._files import write_bytes_atomic
from pytest_emrd._scrub import scrub, scrub_bytes
from pytest_emrd._serde import json_safe
from pytest_emrd.errors import check_choice
from pytest_emrd.gate import Verdict
from pytest_emrd.metrics import EpisodeMetrics
from pytest_emrd.report._build import Prices, align_map, build_report, group_cells
from pytest_emrd.report._compare import (
    COMPARED,
    Comparison,
    compare_document,
    compare_lines,
    compare_runs,
)
from pytest_emrd.report._document import Document, render_html, render_markdown
from pytest_emrd.report._model import FIGURES, Report, row_label
from pytest_emrd.report._sections import START_GATES, report_document, summary_document
from pytest_emrd.run import StoredEpisode
from pytest_emrd.trajectory import Trajectory

if TYPE_CHECKING:
    from pytest_emrd.agent import Registry

__all__ = [
    "COMPARED",
    "FIGURES",
    "START_GATES",
    "Comparison",
    "Report",
    "align_map",
    "append_step_summary",
    "build_report",
    "check_formats",
    "compare_lines",
    "compare_runs",
    "group_cells",
    "registry_prices",
    "render_comparison",
    "render_files",
    "row_label",
    "step_summary_markdown",
    "write_files",
    "write_report",
]


#: Output formats of ``emrd report --format``.
FORMATS: Final[tuple[str, ...]] = ("md", "html", "json")
#: Files scrubbed before they are written (figures are pixels).
TEXT_SUFFIXES: Final = frozenset({".md", ".html", ".json", ".txt", ".csv"})


def check_formats(formats: Iterable[str]) -> list[str]:
    """The requested formats, deduplicated; ConfigError naming an unknown one.

    :param formats: Names among ``md``, ``html``, ``json``.
    :returns: The formats, in first-seen order.
    """
    wanted = list(dict.fromkeys(formats))
    for f in wanted:
        check_choice("format", f, FORMATS, hint="Use a comma-separated list such as md,html.")
    return wanted


def render_files(
    report: Report, formats: Iterable[str] = FORMATS, *, processes: int = 1
) -> dict[str, bytes]:
    """File name -> content: ``report.md`` with its PNGs, ``report.html``, ``report.json``;
    ``processes`` > 1 draws the figures in that many worker processes (same bytes).

    :param report: The report to render.
    :param formats: Which files to render (:func:`check_formats`).
    :param processes: Processes drawing the figures.
    :returns: File name -> bytes.
    """
    wanted = check_formats(formats)
    doc: Document | None = None
    pngs: dict[str, bytes] = {}
    if "md" in wanted or "html" in wanted:
        from pytest_emrd.report._plots import render_figures  # matplotlib: imported on use

        pngs, skipped = render_figures(report, processes=processes)
        doc = report_document(report, skipped)
    return _files("report", wanted, doc, pngs, report)


def _files(
    stem: str,
    wanted: list[str],
    doc: Document | None,
    pngs: dict[str, bytes],
    data: Report | Comparison,
) -> dict[str, bytes]:
    """``<stem>.md`` with the PNGs, ``<stem>.html`` and ``<stem>.json`` (every aggregate as
    strict JSON, non-finite floats as strings), as ``wanted``."""
    files: dict[str, bytes] = {}
    if doc is not None and "md" in wanted:
        files[f"{stem}.md"] = render_markdown(doc).encode()
        files.update(pngs)
    if doc is not None and "html" in wanted:
        files[f"{stem}.html"] = render_html(doc, pngs).encode()
    if "json" in wanted:
        text = json.dumps(json_safe(data.to_dict()), indent=1, allow_nan=False) + "\n"
        files[f"{stem}.json"] = text.encode()
    return files


def step_summary_markdown(
    episodes: Sequence[Trajectory | StoredEpisode],
    verdicts: Sequence[Verdict],
    *,
    thresholds_source: str | None = None,
    episode_metrics: Sequence[EpisodeMetrics] | None = None,
    prices: Prices | None = None,
    gates_note: str | None = None,
) -> str:
    """Markdown for a PR comment or ``$GITHUB_STEP_SUMMARY``: run overview, what is missing,
    the gate table, Exploration Competence and FPSG (no figures, no sentence encoder);
    ``thresholds_source`` names the thresholds file (default ``thresholds`` when there are
    verdicts); ``episode_metrics`` and ``prices`` as :func:`build_report` takes them;
    ``gates_note`` says why no gate ran (a shard).

    :param episodes: The run's episodes.
    :param verdicts: Its gate verdicts.
    :param thresholds_source: The thresholds file's name.
    :param episode_metrics: The episodes' metrics, if measured already.
    :param prices: Model -> USD per million tokens, for the usage table.
    :param gates_note: Why no gate ran, if none did.
    :returns: The Markdown text.
    """
    source = thresholds_source or ("thresholds" if verdicts else None)
    report = build_report(
        episodes,
        verdicts=verdicts,
        thresholds_source=source,
        with_reasoning=False,
        episode_metrics=episode_metrics,
        prices=prices,
    )
    report = dataclasses.replace(report, gates=dataclasses.replace(report.gates, note=gates_note))
    return render_markdown(summary_document(report))


def registry_prices(registry: Registry, models: Iterable[str]) -> Prices:
    """Model -> (USD per million input tokens, per million output) of each model ``registry``
    knows (a model it does not know has no price).

    :param registry: The model registry.
    :param models: The models of the run.
    :returns: Model -> ``(input, output)`` USD per million tokens.
    """
    configs = {m: registry.get(m) for m in models if m in registry.names()}
    return {m: (c.price_per_mtok_in, c.price_per_mtok_out) for m, c in configs.items()}


def render_comparison(comparison: Comparison, formats: Iterable[str] = FORMATS) -> dict[str, bytes]:
    """File name -> content of a run comparison: ``compare.md``, ``.html``, ``.json``.

    :param comparison: The result of :func:`compare_runs`.
    :param formats: Which files to render.
    :returns: File name -> bytes.
    """
    return _files("compare", check_formats(formats), compare_document(comparison), {}, comparison)


def write_files(files: Mapping[str, bytes], out_dir: Path) -> list[Path]:
    """Write each ``name -> content`` into ``out_dir`` (created if needed), atomically; text
    files are scrubbed of secrets first (a report quotes errored episodes' causes).

    :param files: File name -> content.
    :param out_dir: The folder to write into.
    :returns: The paths written.
    """
    for name, content in files.items():
        text = Path(name).suffix in TEXT_SUFFIXES
        write_bytes_atomic(out_dir / name, scrub_bytes(content) if text else content)
    return [out_dir / name for name in files]


def append_step_summary(text: str) -> bool:
    """Append ``text`` (Markdown, scrubbed of secrets) to ``$GITHUB_STEP_SUMMARY``; ``False``
    when it is not set.

    :param text: Markdown to append.
    :returns: Whether it was written.
    """
    target = os.environ.get("GITHUB_STEP_SUMMARY")
    if not target:
        return False
    text = scrub(text)
    with open(target, "a", encoding="utf-8") as summary:
        summary.write(text if text.endswith("\n") else text + "\n")
    return True


def write_report(
    report: Report, out_dir: Path, formats: Iterable[str] = FORMATS, *, processes: int = 1
) -> list[Path]:
    """Render ``report`` in ``formats`` (figures drawn in ``processes`` processes) and write it
    into ``out_dir``; the paths written.

    :param report: The report.
    :param out_dir: The folder to write into.
    :param formats: Which files to write.
    :param processes: Processes drawing the figures.
    :returns: The paths written.
    """
    return write_files(render_files(report, formats, processes=processes), out_dir)
