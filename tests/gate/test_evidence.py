"""A failed gate points at its evidence: its worst episodes, the `emrd view` command that opens
them, and why a CI bound cannot be met with too few episodes (underpowered)."""

from __future__ import annotations

from dataclasses import dataclass

import pytest

from pytest_emrd.gate import Bound, GateCell, evaluate_cell, gate_tables, judge
from pytest_emrd.trajectory import EpisodeSpec

from .conftest import Estimate


@dataclass(frozen=True)
class Episode:
    spec: EpisodeSpec
    aec: float | None


@dataclass(frozen=True)
class MeanAec:
    name: str = "aec"
    better: str = "higher"

    def compute(self, items, *, rng_seed: int = 0) -> Estimate:
        values = [e.aec for e in items if e.aec is not None]
        return Estimate(sum(values) / len(values), min(values), max(values), len(values))


EPISODES = [
    Episode(EpisodeSpec("scout", "baseline", spawn, ep), aec)
    for (spawn, ep), aec in zip(
        [(s, e) for s in ("office", "kitchen", "entrance", "conference") for e in range(2)],
        [0.9, 0.2, 0.8, None, 0.5, 0.95, 0.3, 0.7],
        strict=True,
    )
]


def test_a_failed_gate_lists_its_worst_episodes_and_the_view_command():
    cell = GateCell(Bound("scout", "baseline", "aec", "min", 0.99))
    verdict = evaluate_cell(cell, EPISODES, {"aec": MeanAec()}, run_dir_of=lambda c: "runs/a b")
    assert not verdict.passed
    worst = [case.removeprefix("scout-baseline-") for case, _ in verdict.worst]
    assert worst == [
        "office-ep01",
        "conference-ep00",
        "entrance-ep00",
        "conference-ep01",
        "kitchen-ep00",
    ]
    assert verdict.worst[0][1] == 0.2
    assert verdict.view == (
        "emrd view 'runs/a b' scout-baseline-office-ep01 scout-baseline-conference-ep00 "
        "scout-baseline-entrance-ep00 scout-baseline-conference-ep01 scout-baseline-kitchen-ep00"
    )
    text = "\n".join(gate_tables([verdict]))
    assert "worst episodes by aec: scout-baseline-office-ep01 (0.2)" in text
    assert f"open them: `{verdict.view}`" in text


def test_a_passed_gate_lists_no_episodes():
    cell = GateCell(Bound("scout", "baseline", "aec", "min", 0.1))
    verdict = evaluate_cell(cell, EPISODES, {"aec": MeanAec()})
    assert verdict.passed and verdict.worst == () and verdict.evidence() == []


@pytest.mark.parametrize(
    ("estimate", "says"),
    [
        (Estimate(0.9, 0.878, 0.95, 3), "about 4 episodes in the cell"),
        (Estimate(1.0, None, None, 1), "a CI bound needs at least 2 episodes"),
    ],
    ids=["spread", "one-episode"],
)
def test_an_underpowered_ci_gate_fails_and_says_how_many_episodes_it_needs(estimate, says):
    verdict = judge(GateCell(Bound("scout", "baseline", "aec", "min", 0.88, "lower")), estimate)
    assert not verdict.passed and says in verdict.reason


def test_a_gate_whose_value_fails_is_not_called_underpowered():
    estimate = Estimate(0.85, 0.8, 0.9, 3)
    verdict = judge(GateCell(Bound("scout", "baseline", "aec", "min", 0.88, "lower")), estimate)
    assert not verdict.passed and "underpowered" not in verdict.reason
