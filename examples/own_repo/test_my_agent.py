"""Your own EMRD tests: per-episode checks, a custom metric and a custom gate.

pytest-emrd's fixtures work in any repository that has the package installed (the plugin
registers itself); no thresholds.yaml is needed. The same ``--emrd-*`` options pick the
grid, for example::

    pytest tests/test_my_agent.py --emrd-model=gemini --emrd-condition=baseline -n 2

Fixtures used here:

* ``emrd_trajectory`` -- parametrises the test over the grid's episodes
  (``test_...[gemini-baseline-office-ep03]``) and gives each episode's trajectory,
  recorded or replayed through its cassette and shared with every other test that asks.
* ``emrd_trajectories(model, condition)`` -- every trajectory of one cell, for gates.
* ``emrd_settings`` -- the resolved options (``models``, ``conditions``, ``episodes`` ...).
"""

from __future__ import annotations

import math

import pytest

from pytest_emrd.metrics import bootstrap_ci
from pytest_emrd.trajectory import Trajectory

#: The custom gate: the mean action success rate's 95 % CI lower end stays above this.
MIN_ACTION_SUCCESS = 0.6


def action_success_rate(trajectory: Trajectory) -> float | None:
    """Custom metric: the fraction of steps whose action the world executed.

    ``sum(step.success) / len(steps)``; ``None`` for an episode without steps (errored
    before its first reply), never a silent 0.
    """
    if not trajectory.steps:
        return None
    return math.fsum(step.success for step in trajectory.steps) / len(trajectory.steps)


def test_the_gathering_room_was_entered(emrd_trajectory: Trajectory) -> None:
    """Per episode: a named gathering room is one the agent stood in (a grounded choice)."""
    if emrd_trajectory.status != "terminated":
        pytest.skip(f"{emrd_trajectory.spec.case_id} ended {emrd_trajectory.status}")
    entered = {step.room for step in emrd_trajectory.steps}
    assert emrd_trajectory.chosen_room in entered, (
        f"{emrd_trajectory.spec.case_id} chose {emrd_trajectory.chosen_room} without entering it"
    )


@pytest.mark.parametrize("condition", ["baseline"])
def test_action_success_gate(emrd_trajectories, emrd_settings, condition: str) -> None:
    """Custom gate: per model, the 95 % CI of the mean action success rate clears the bound."""
    for model in emrd_settings.models:
        rates = [
            rate
            for t in emrd_trajectories(model, condition)
            if t.status != "errored" and (rate := action_success_rate(t)) is not None
        ]
        assert len(rates) >= 2, f"{model}/{condition}: too few episodes for a CI"
        low, high = bootstrap_ci(rates, rng_seed=0)
        mean = math.fsum(rates) / len(rates)
        assert low is not None and low >= MIN_ACTION_SUCCESS, (
            f"{model}/{condition}: action success {mean:.3f}, 95% CI [{low:.3f}, {high:.3f}], "
            f"n={len(rates)}; the gate needs the CI's lower end >= {MIN_ACTION_SUCCESS}"
        )
