"""The metrics stage's workload runs end to end (timings come from ``python -m perf``)."""

from __future__ import annotations

import pytest

from perf.metrics import all_metrics, run
from pytest_emrd.metrics import GATE_METRICS, Estimate
from pytest_emrd.metrics.synthetic import synthetic_grid


def test_all_metrics_computes_every_gate_and_aggregate() -> None:
    results = all_metrics(synthetic_grid(episodes=3))
    assert set(GATE_METRICS) <= set(results)
    assert all(isinstance(results[name], Estimate) for name in GATE_METRICS)
    assert {"tbs_curve", "kaplan_meier_anchored", "miller_curve", "anova_conditions"} <= set(
        results
    )


@pytest.mark.slow
def test_run_reports_warm_and_cold_figures_against_their_targets() -> None:
    figures = {f.figure: f for f in run(repeat=1, warmup=1, episodes=2)}
    targets = {name: f.target for name, f in figures.items()}
    assert targets == {
        "metrics.grid_240_s": 3.0,
        "metrics.gate_320_cold_s": 4.0,
        "metrics.gate_320_cold_cpu_s": None,
        "metrics.gate_320_s": None,
        "metrics.gate_320_cold_ratio": 1.3,
    }
    assert all(f.value > 0 and f.n == 1 for f in figures.values())
