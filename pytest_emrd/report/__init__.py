"""Reports: the paper's tables and figures from any run.

Compute (pure): :func:`build_report` (a :class:`Report` of the metrics library's results),
:func:`compare_runs`. Render (pure): :func:`render_files` (Markdown + PNG, self-contained
HTML, JSON), :func:`render_comparison`, :func:`step_summary_markdown`. Write (I/O):
:func:`write_report`, :func:`write_files`.

Typical use::

    trajectories = pytest_emrd.run.load_run_dirs([Path("results/run1")])
    write_report(build_report(trajectories), Path("results/run1/report"))
"""

from pytest_emrd.report._build import align_map, build_report, group_cells
from pytest_emrd.report._compare import COMPARED, Comparison, Difference, compare_runs
from pytest_emrd.report._model import FIGURES, Report, row_label
from pytest_emrd.report._render import (
    FORMATS,
    append_step_summary,
    check_formats,
    render_comparison,
    render_files,
    report_json,
    step_summary_markdown,
    write_files,
    write_report,
)

__all__ = [
    "COMPARED",
    "FIGURES",
    "FORMATS",
    "Comparison",
    "Difference",
    "Report",
    "align_map",
    "append_step_summary",
    "build_report",
    "check_formats",
    "compare_runs",
    "group_cells",
    "render_comparison",
    "render_files",
    "report_json",
    "row_label",
    "step_summary_markdown",
    "write_files",
    "write_report",
]
