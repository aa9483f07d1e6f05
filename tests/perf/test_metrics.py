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
def test_run_reports_the_grid_figure_against_its_target() -> None:
    (figure,) = run(repeat=1, warmup=1)
    assert figure.figure == "metrics.grid_240_s"
    assert (figure.unit, figure.target, figure.n) == ("s", 2.0, 1)
    assert figure.value > 0
