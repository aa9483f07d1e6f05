"""The docs' performance table, generated from ``python -m perf --json``.

``python perf/table.py FILE`` prints the Markdown table of the figures in ``FILE``; as an
MkDocs hook (``hooks:`` in ``mkdocs.yml``) it replaces :data:`MARKER` in any page with the
table of :data:`FIGURES` (``docs/performance.json``), so the page never holds a number by
hand. Regenerate the figures with ``python -m perf all --json > docs/performance.json``.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path
from typing import Any

#: Where the docs read the figures from: the JSON ``python -m perf --json`` prints.
FIGURES = Path(__file__).resolve().parents[1] / "docs" / "performance.json"
#: The line of a docs page the table replaces.
MARKER = "<!-- performance-table -->"
COLD = "_cold"

#: What each figure measures, by warm name (its ``_cold`` twin is the same measurement).
ABOUT: dict[str, str] = {
    "world.step_ms": "render + JPEG + pixel digest, one step",
    "world.render_ms": "the renderer alone, one 512×512 frame",
    "world.episode_s": "50 steps as a replay runs them (no JPEG)",
    "world.layout_ms": "one generated office",
    "loop.step_overhead_ms": "prompt, data URL, body encoding, parse, bookkeeping",
    "loop.episode_s": "one scout episode against the local reference server",
    "metrics.grid_240_s": "every metric, 240 synthetic episodes × 50 steps",
    "metrics.gate_320_cold_s": "`emrd gate` on the committed 320-episode run: fresh process, "
    "no bytecode cache",
    "metrics.gate_320_cold_cpu_s": "its CPU time, over every core",
    "metrics.gate_320_s": "the same command with its bytecode cached",
    "metrics.gate_320_cold_ratio": "cold over warm",
    "replay.grid_240_s": "`pytest benchmarks -n 2`: the default grid replayed, gates included",
    "replay.grid_240_cpu_s": "its CPU time, controller and workers",
    "replay.resume_240_s": "the same command again on the finished run directory",
    "replay.resume_240_cpu_s": "its CPU time",
    "replay.resume_240_nobytecode_s": "the same with `PYTHONDONTWRITEBYTECODE=1`",
    "replay.vs_world_ratio": "12 committed episodes replayed / the world alone (CPU time)",
    "replay.httpx_vcrpy_floor_vs_world_ratio": "the same with httpx and vcrpy alone answering",
    "replay.cassette_kb_per_episode": "committed scout cassettes, mean size",
    "replay.cassette_kb_per_50_steps": "a 50-step episode's cassette (size-vs-steps line)",
    "replay.size_ratio_vs_plain_vcrpy": "committed cassettes vs plain vcrpy YAML, same traffic",
    "replay.step_overhead_ms": "per replayed request: encode, redact, match, rebuild, parse",
    "live.concurrency_16_vs_floor": "64 live episodes, 16 at once, 0.5 s per call: wall / floor",
    "plugin.collect_7x240_s": "`pytest benchmarks --collect-only`, 7 models × 240 cases",
    "plugin.collect_7x240_cpu_s": "its CPU time",
    "plugin.collect_7x240_nobytecode_s": "the same with `PYTHONDONTWRITEBYTECODE=1`",
    "plugin.empty_session_s": "the floor: pytest and its other plugins on an empty file",
    "plugin.empty_session_cpu_s": "its CPU time",
    "plugin.empty_session_nobytecode_s": "the floor with `PYTHONDONTWRITEBYTECODE=1`",
    "report.grid_240_s": "`emrd report` on a 240-episode run, whole process",
    "report.grid_240_cpu_s": "its CPU time",
    "report.grid_240_nobytecode_s": "the same with `PYTHONDONTWRITEBYTECODE=1`",
}


def _value(figure: dict[str, Any] | None) -> str:
    if figure is None:
        return "—"
    unit = {"ratio": "", "s": " s", "ms": " ms", "KB": " KB"}.get(figure["unit"], "")
    value = float(figure["value"])
    if figure["unit"] == "ratio" and value >= 100:
        return f"{value:.0f}×"
    return f"{value:.3g}{unit}"


def _met(figure: dict[str, Any] | None) -> str:
    if figure is None or figure["target"] is None:
        return ""
    above = float(figure["value"]) >= float(figure["target"])
    return "yes" if above == bool(figure.get("higher_is_better")) else "**no**"


def markdown_table(figures: list[dict[str, Any]]) -> str:
    """One row per measurement: its warm and cold value, target and whether each meets it."""
    by_name = {f["figure"]: f for f in figures}
    first: dict[str, dict[str, Any]] = {}  # measurement -> its first figure, warm or cold
    for figure in figures:
        first.setdefault(figure["figure"].removesuffix(COLD), figure)
    rows = [
        "| figure | what | warm | cold | target | met (warm / cold) | n |",
        "|---|---|---:|---:|---:|---|---|",
    ]
    for name, any_one in first.items():
        warm, cold = by_name.get(name), by_name.get(name + COLD)
        target = any_one["target"]
        bound = "—" if target is None else ("≥ " if any_one.get("higher_is_better") else "≤ ")
        bound += "" if target is None else f"{float(target):g}"
        met = " / ".join(m for m in (_met(warm), _met(cold)) if m)
        n = " / ".join(str(f["n"]) for f in (warm, cold) if f is not None)
        rows.append(
            f"| `{name}` | {ABOUT.get(name, '')} | {_value(warm)} | {_value(cold)} "
            f"| {bound} | {met} | {n} |"
        )
    return "\n".join(rows)


def on_page_markdown(markdown: str, **_: object) -> str:
    """MkDocs hook: the table of :data:`FIGURES` in place of :data:`MARKER`."""
    if MARKER not in markdown:
        return markdown
    return markdown.replace(MARKER, markdown_table(json.loads(FIGURES.read_text())))


if __name__ == "__main__":
    print(markdown_table(json.loads(Path(sys.argv[1]).read_text())))
