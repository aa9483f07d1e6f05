"""The docs' performance table is generated from ``python -m perf --json``."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

import perf.table
from perf import Figure
from perf.table import MARKER, markdown_table, on_page_markdown


def _figures() -> list[dict[str, object]]:
    return [
        Figure("world.step_ms", 3.2, "ms", 15.0, 3).to_dict(),
        Figure("replay.size_ratio_vs_plain_vcrpy", 582.4, "ratio", 500.0, 24, True).to_dict(),
        Figure("plugin.collect_7x240_s", 1.7, "s", 1.5, 3).to_dict(),
        Figure("world.step_ms_cold", 41.0, "ms", 15.0, 3).to_dict(),
        Figure("replay.size_ratio_vs_plain_vcrpy_cold", 582.4, "ratio", 500.0, 1, True).to_dict(),
    ]


def test_one_row_per_measurement_with_its_warm_and_cold_value() -> None:
    rows = markdown_table(_figures()).splitlines()[2:]
    assert [row.split(" | ")[0] for row in rows] == [
        "| `world.step_ms`",
        "| `replay.size_ratio_vs_plain_vcrpy`",
        "| `plugin.collect_7x240_s`",
    ]
    step, ratio, collect = rows
    assert "| 3.2 ms | 41 ms | ≤ 15 | yes / **no** | 3 / 3 |" in step
    assert "| 582× | 582× | ≥ 500 | yes / yes | 24 / 1 |" in ratio
    assert "| 1.7 s | — | ≤ 1.5 | **no** | 3 |" in collect


def test_the_hook_replaces_only_the_marker(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    figures = tmp_path / "performance.json"
    figures.write_text(json.dumps(_figures()))
    monkeypatch.setattr(perf.table, "FIGURES", figures)
    page = on_page_markdown(f"# Performance\n\n{MARKER}\n\nAfter.\n")
    assert MARKER not in page and "| `world.step_ms` |" in page and page.endswith("After.\n")
    assert on_page_markdown("# Other page\n") == "# Other page\n"
