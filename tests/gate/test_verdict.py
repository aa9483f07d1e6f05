"""Verdicts: bound comparison, undefined estimates, order independence, tables."""

from __future__ import annotations

import pytest

from pytest_emrd.gate import (
    Bound,
    GateCell,
    Thresholds,
    UsageRow,
    Verdict,
    evaluate_all,
    evaluate_cell,
    gate_tables,
    judge,
    usage_table,
)
from pytest_emrd.trajectory import EpisodeSpec
from tests.run.conftest import make_trajectory

from .conftest import Estimate


def _cell(kind: str, value: float, ci: str | None = None, variant: str = "default") -> GateCell:
    return GateCell(Bound("scout", "baseline", "aec", kind, value, ci), variant)


@pytest.mark.parametrize(
    ("cell", "estimate", "passed", "reason"),
    [
        (_cell("min", 0.8), Estimate(0.9, 0.7, 0.95, 80), True, "value 0.9 >= 0.8"),
        (_cell("min", 0.8), Estimate(0.8, 0.7, 0.95, 80), True, "value 0.8 >= 0.8"),
        (_cell("min", 0.8, "lower"), Estimate(0.75, 0.7, 0.9, 80), False, "CI lower end 0.7 < 0.8"),
        (_cell("max", 0.1), Estimate(0.2, 0.1, 0.3, 80), False, "value 0.2 > 0.1"),
        (
            _cell("max", 0.1, "upper"),
            Estimate(0.05, 0.0, 0.09, 80),
            True,
            "CI upper end 0.09 <= 0.1",
        ),
        (
            _cell("min", 0.8),
            Estimate(None, None, None, 0, "no re-entries"),
            False,
            "value undefined: no re-entries",
        ),
    ],
    ids=["min-pass", "min-equal", "ci-lower-fail", "max-fail", "ci-upper-pass", "undefined-fails"],
)
def test_judge(cell, estimate, passed, reason):
    verdict = judge(cell, estimate)
    assert verdict.passed is passed and verdict.reason == reason
    assert Verdict.from_dict(verdict.to_dict()) == verdict


def test_gate_id_names_variant_only_when_not_default():
    assert _cell("min", 1).gate_id == "scout-baseline-aec"
    assert _cell("min", 1, variant="B2").gate_id == "scout-baseline-B2-aec"


def _episodes(model: str = "scout", condition: str = "baseline"):
    return [
        make_trajectory(EpisodeSpec(model, condition, spawn, ep))
        for spawn in ("office", "kitchen")
        for ep in range(3)
    ]


def test_cell_verdict_does_not_depend_on_episode_order(metrics):
    cell = GateCell(Bound("scout", "baseline", "steps", "max", 5.0))
    episodes = _episodes()
    assert evaluate_cell(cell, episodes, metrics) == evaluate_cell(cell, episodes[::-1], metrics)


def test_evaluate_all_matches_cell_by_cell(metrics):
    bounds = (
        Bound("scout", "baseline", "steps", "max", 5.0),
        Bound("scout", "texture", "steps", "min", 1.0),
    )
    episodes = _episodes() + _episodes(condition="texture")
    verdicts = evaluate_all(episodes[::-1], Thresholds("t.yaml", bounds), metrics)
    assert [v.gate_id for v in verdicts] == ["scout-baseline-steps", "scout-texture-steps"]
    assert verdicts[0] == evaluate_cell(GateCell(bounds[0]), episodes[:6], metrics)
    assert not verdicts[1].passed and verdicts[1].n == 6


def test_gate_table_lists_every_gate_and_explains_failures():
    verdicts = [
        judge(_cell("min", 0.8), Estimate(0.9, 0.85, 0.95, 80)),
        judge(_cell("max", 0.1), Estimate(0.2, 0.1, 0.3, 80)),
    ]
    lines = gate_tables(verdicts)
    assert lines[0] == "scout: 1/2 gates pass"
    assert "condition" in lines[1] and "bound" in lines[1]
    assert any("PASS" in line and ">= 0.8" in line for line in lines)
    assert lines[-1] == "  FAIL scout-baseline-aec: value 0.2 > 0.1"


def test_usage_table_shows_cost_only_when_known():
    lines = usage_table(
        [UsageRow("gpt", 2, 1_000_000, 2_000, 2.5), UsageRow("scout", 2, 10, 5, None)]
    )
    assert "1,000,000" in lines[1] and "$2.50" in lines[1] and "n/a" in lines[2]
