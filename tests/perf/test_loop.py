"""``python -m perf loop`` produces its two figures (the harness measures the values)."""

from __future__ import annotations

from perf import run_stages


def test_loop_bench_reports_both_figures() -> None:
    figures = {f.figure: f for f in run_stages(["loop"], repeat=1)}
    assert set(figures) == {"loop.step_overhead_ms", "loop.episode_s"}
    assert figures["loop.step_overhead_ms"].unit == "ms"
    assert figures["loop.episode_s"].unit == "s"
    assert all(f.value > 0 and f.n == 1 and f.target for f in figures.values())
