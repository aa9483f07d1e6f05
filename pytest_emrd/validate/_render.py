"""The validation table as Markdown (printed and written) and JSON text."""

from __future__ import annotations

import json
from collections import Counter

from pytest_emrd._serde import json_safe
from pytest_emrd.validate._check import ValidationReport

_COLUMNS = ("Check", "Planted", "Recovered", "Tolerance", "Verdict", "Note")


def _cell(text: str) -> str:
    return text.replace("|", "\\|").replace("\n", " ")


def markdown(report: ValidationReport) -> str:
    """One Markdown table per paper phase, then a one-line summary."""
    lines: list[str] = []
    section = None
    for c in report.checks:
        if c.section != section:
            section = c.section
            lines += ["", f"### {section}", "", "| " + " | ".join(_COLUMNS) + " |",
                      "|" + "---|" * len(_COLUMNS)]  # fmt: skip
        verdict = f"**{c.verdict}**" if c.verdict != "pass" else c.verdict
        cells = (c.name, c.planted, c.recovered, c.tolerance, verdict, c.note)
        lines.append("| " + " | ".join(_cell(x) for x in cells) + " |")
    counts = Counter(c.verdict for c in report.checks)
    summary = ", ".join(f"{counts[v]} {v}" for v in ("pass", "fail", "finding") if counts[v])
    head = f"{len(report.checks)} checks: {summary}"
    if report.episodes:
        head += (
            f" ({report.episodes} episodes per spawn room and agent, protocol {report.protocol})"
        )
    return "\n".join([head, *lines]) + "\n"


def to_json(report: ValidationReport) -> str:
    """The report as indented, strict JSON (:meth:`ValidationReport.to_dict`); unbounded and
    undefined numbers (an EFC with no forgetting event) are the strings ``"inf"``/``"nan"``."""
    return json.dumps(json_safe(report.to_dict()), indent=2, allow_nan=False) + "\n"
