"""``emrd thresholds``: a starter file the runs it came from pass and a clear regression fails."""

from __future__ import annotations

import dataclasses

import pytest

from pytest_emrd.gate import evaluate_all, parse_thresholds, starter_thresholds
from pytest_emrd.metrics import GATE_METRICS, as_episode_metrics
from pytest_emrd.metrics.synthetic import synthetic_grid


@pytest.fixture(scope="module")
def grid():
    return as_episode_metrics(synthetic_grid(model="syn", episodes=3, max_steps=30))


def _parse(text: str):
    return parse_thresholds(
        text, source="t.yaml", is_model=lambda m: True, model_names=(), metrics=GATE_METRICS
    )


def test_the_run_passes_its_starter_and_a_regression_fails(grid) -> None:
    text = starter_thresholds(grid, GATE_METRICS, command="emrd thresholds run")
    assert text.startswith("# Starter gates written by `emrd thresholds run` from 36 episodes.")
    assert "syn:\n  baseline:\n    aec: {min: " in text and "  # " in text
    thresholds = _parse(text)
    verdicts = evaluate_all(grid, thresholds, GATE_METRICS)
    assert verdicts and all(v.passed for v in verdicts), [v.explain() for v in verdicts]
    episodes = synthetic_grid(model="syn", episodes=3, max_steps=30)
    quit_early = as_episode_metrics([dataclasses.replace(t, steps=t.steps[:3]) for t in episodes])
    failed = {v.metric for v in evaluate_all(quit_early, thresholds, GATE_METRICS) if not v.passed}
    assert "aec" in failed
