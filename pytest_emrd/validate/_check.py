"""One row of the validation table (what was planted, what the metric recovered, the verdict),
and the table as Markdown (printed and written) and JSON text."""

from __future__ import annotations

import itertools
import json
import math
from collections import Counter
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Final

from pytest_emrd._serde import JsonRecord, Schema, json_safe
from pytest_emrd.errors import check_choice
from pytest_emrd.metrics import EpisodeMetrics
from pytest_emrd.trajectory import Trajectory

SCHEMA_VERSION: Final = 1
#: ``pass``/``fail``: the metric recovered / did not recover the planted truth.
#: ``finding``: the paper does not hold up at this point, while our metric does: a value the
#: paper prints is not reproducible from the counts it prints (the note says which value,
#: what the printed counts give, and what would reproduce it), or the paper's estimator
#: misreads a planted truth that our estimator recovers (the note says how).
VERDICTS: Final = ("pass", "fail", "finding")
SECTIONS: Final = ("Explore", "Map", "Remember", "Decide", "Replies", "Statistics")

Value = float | int | str | None
#: What the checks read: a trajectory, or its metrics computed once (much faster).
Episode = Trajectory | EpisodeMetrics
#: One group's episodes.
Episodes = Sequence[Episode]


@dataclass(frozen=True, kw_only=True)
class Check:
    """One validation check, as the table shows it and the JSON stores it."""

    section: str
    """Paper phase the metric belongs to (:data:`SECTIONS`); ``Replies``: reading the replies."""
    name: str
    """What is checked (``Ebbinghaus EFC, scout-decay-8``)."""
    planted: str
    """The known truth (planted parameter, or the value the paper prints)."""
    recovered: str
    tolerance: str
    """The acceptance rule, in words (``within 25 %``, ``printed precision``)."""
    verdict: str
    """``pass``, ``fail`` or ``finding`` (see :data:`VERDICTS`)."""
    note: str = ""
    """Episodes used, why it failed, what reproduces a printed value."""
    data: dict[str, Value] = field(default_factory=dict)
    """The raw numbers behind ``planted`` / ``recovered`` (for JSON consumers)."""

    def __post_init__(self) -> None:
        check_choice("verdict", self.verdict, VERDICTS)
        check_choice("section", self.section, SECTIONS)

    @property
    def failed(self) -> bool:
        return self.verdict == "fail"


@dataclass(frozen=True)
class ValidationReport(JsonRecord):
    """Every check of one validation run."""

    schema = Schema(
        SCHEMA_VERSION,
        "validation report",
        "rerun emrd validate with this version of pytest-emrd.",
    )

    checks: tuple[Check, ...]
    episodes: int
    """Episodes per spawn room and planted agent (0 for statistics-only reports)."""
    protocol: str
    """World + prompt protocol the episodes ran under."""
    schema_version: int = SCHEMA_VERSION

    @property
    def failed(self) -> tuple[Check, ...]:
        return tuple(c for c in self.checks if c.failed)


def judged(ok: bool) -> str:
    """``pass`` when ``ok``, else ``fail``."""
    return "pass" if ok else "fail"


def fmt(value: float | None, digits: int = 2) -> str:
    """A number for the table: fixed ``digits``, ``inf`` and ``n/a`` spelled out."""
    if value is None or math.isnan(value):
        return "n/a"
    if math.isinf(value):
        return "inf"
    return f"{value:.{digits}f}"


def max_gap(a: Sequence[float | None], b: Sequence[float | None]) -> float:
    """Largest ``|a_i - b_i|``; ``inf`` when the two differ in length, in which are undefined,
    or in an infinite value (equal infinities differ by 0)."""
    if len(a) != len(b):
        return math.inf
    gaps = [0.0]
    for x, y in zip(a, b, strict=True):
        if (x is None) != (y is None):
            return math.inf
        if x is not None and y is not None and x != y:  # inf - inf would be nan
            gaps.append(abs(x - y))
    return max(gaps)


def pct(value: float | None) -> str:
    """A fraction in [0, 1] as a percentage with one decimal."""
    return "n/a" if value is None else f"{100.0 * value:.1f} %"


_COLUMNS: Final = ("Check", "Planted", "Recovered", "Tolerance", "Verdict", "Note")


def _row(cells: Sequence[str]) -> str:
    return "| " + " | ".join(c.replace("|", "\\|").replace("\n", " ") for c in cells) + " |"


def markdown(report: ValidationReport) -> str:
    """One Markdown table per paper phase, then a one-line summary.

    :param report: The validation report.
    :returns: The Markdown text.
    """
    lines: list[str] = []
    for section, checks in itertools.groupby(report.checks, key=lambda c: c.section):
        lines += ["", f"### {section}", "", _row(_COLUMNS), "|" + "---|" * len(_COLUMNS)]
        for c in checks:
            verdict = f"**{c.verdict}**" if c.verdict != "pass" else c.verdict
            lines.append(_row((c.name, c.planted, c.recovered, c.tolerance, verdict, c.note)))
    counts = Counter(c.verdict for c in report.checks)
    summary = ", ".join(f"{counts[v]} {v}" for v in VERDICTS if counts[v])
    head = f"{len(report.checks)} checks: {summary}"
    if report.episodes:
        head += (
            f" ({report.episodes} episodes per spawn room and agent, protocol {report.protocol})"
        )
    return "\n".join([head, *lines]) + "\n"


def to_json(report: ValidationReport) -> str:
    """The report as indented, strict JSON (:meth:`ValidationReport.to_dict`); unbounded and
    undefined numbers (an EFC with no forgetting event) are the strings ``"inf"``/``"nan"``.

    :param report: The validation report.
    :returns: The JSON text.
    """
    return json.dumps(json_safe(report.to_dict()), indent=2, allow_nan=False) + "\n"
