"""``emrd bench loop`` produces its two figures (values are measured by the bench, not here)."""

from __future__ import annotations

from pytest_emrd.bench import run_stages


def test_loop_bench_reports_both_figures() -> None:
    figures = {f.figure: f for f in run_stages(["loop"], repeat=1)}
    assert set(figures) == {"loop.step_overhead_ms", "loop.episode_s"}
    assert figures["loop.step_overhead_ms"].unit == "ms"
    assert figures["loop.episode_s"].unit == "s"
    assert all(f.value > 0 and f.n == 1 and f.target for f in figures.values())
