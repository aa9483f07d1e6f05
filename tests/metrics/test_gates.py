"""The gate-metric registry: names, estimates, CIs, exclusions, reasons."""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
import pytest

from pytest_emrd.errors import ConfigError
from pytest_emrd.metrics import (
    GATE_METRICS,
    EpisodeMetrics,
    Estimate,
    ebbinghaus_fit,
    evaluate_gates,
)
from pytest_emrd.metrics._gates import _r2_of_histograms
from pytest_emrd.rooms import OFFICE
from pytest_emrd.trajectory import GroundTruthObject, Trajectory

MakeObj = Callable[..., GroundTruthObject]
MakeTraj = Callable[..., Trajectory]

REQUIRED = {"aec", "te", "pa", "fpsg_local", "fpsg_global", "never_visited", "any_bias", "sir",
            "memory_strength", "ebbinghaus_r2", "consensus", "parse_failure_rate",
            "errored_rate"}  # fmt: skip


def test_registry_names_and_fields() -> None:
    assert set(GATE_METRICS) >= REQUIRED
    for name, metric in GATE_METRICS.items():
        assert metric.name == name
        assert metric.better in ("higher", "lower")
        assert metric.unit in ("fraction", "steps", "R^2")
        assert metric.description


@pytest.mark.parametrize("name", sorted(REQUIRED))
def test_every_gate_on_a_synthetic_grid(
    name: str, small_grid_metrics: list[EpisodeMetrics]
) -> None:
    est = GATE_METRICS[name].compute(small_grid_metrics, rng_seed=1)
    assert isinstance(est, Estimate)
    assert est.value is not None and math.isfinite(est.value)
    assert est.ci_low is not None and est.ci_high is not None
    assert est.ci_low <= est.value + 1e-9 and est.value - 1e-9 <= est.ci_high
    if GATE_METRICS[name].unit == "fraction":
        assert 0.0 <= est.ci_low <= est.value <= est.ci_high <= 1.0
    assert est == GATE_METRICS[name].compute(small_grid_metrics, rng_seed=1)


def test_trajectories_and_episode_metrics_give_the_same_estimates(
    small_grid: list[Trajectory], small_grid_metrics: list[EpisodeMetrics]
) -> None:
    names = ["aec", "memory_strength", "consensus"]
    assert evaluate_gates(small_grid[:6], names) == evaluate_gates(small_grid_metrics[:6], names)


def test_errored_episodes_are_excluded_and_counted(make_obj: MakeObj, make_traj: MakeTraj) -> None:
    ok = make_traj([make_obj("Desk_1")], [(OFFICE, ["Desk_1"], {"d": ("Desk", 0.0, 0.0)})])
    bad = make_traj([make_obj("Desk_1")], [], status="errored", error="cassette missing")
    aec = GATE_METRICS["aec"].compute([ok, bad])
    assert (aec.value, aec.n, aec.excluded) == (1.0, 1, 1)
    assert aec.ci_low is None and aec.reason == "one episode: no confidence interval"
    rate = GATE_METRICS["errored_rate"].compute([ok, bad])
    assert (rate.value, rate.n) == (0.5, 2)


def test_undefined_everywhere_gives_none_with_the_reason(
    make_obj: MakeObj, make_traj: MakeTraj
) -> None:
    traj = make_traj([make_obj("Desk_1")], [(OFFICE, ["Desk_1"], {})] * 2)
    sir = GATE_METRICS["sir"].compute([traj])
    assert sir.value is None
    assert sir.reason == "undefined in every episode (no room was re-entered)"
    assert GATE_METRICS["memory_strength"].compute([traj]).value is None
    assert GATE_METRICS["aec"].compute([]).reason == "no non-errored episode"


def test_memory_strength_without_events_is_unbounded(
    make_obj: MakeObj, make_traj: MakeTraj
) -> None:
    held = {"d": ("Desk", 0.0, 0.0)}
    traj = make_traj([make_obj("Desk_1")], [(OFFICE, ["Desk_1"], held), (OFFICE, [], held)])
    est = GATE_METRICS["memory_strength"].compute([traj, traj])
    assert est.value == math.inf and est.reason is not None and "unbounded" in est.reason


def test_evaluate_gates_rejects_unknown_names(small_grid_metrics: list[EpisodeMetrics]) -> None:
    with pytest.raises(ConfigError, match="metric='coverage'"):
        evaluate_gates(small_grid_metrics, ["aec", "coverage"])


def test_vectorised_r2_bootstrap_agrees_with_the_scalar_fit(
    small_grid_metrics: list[EpisodeMetrics],
) -> None:
    spells = [s for m in small_grid_metrics for s in m.ttf_spells]
    mapped = sum(sum(m.mapped_by_category.values()) for m in small_grid_metrics)
    total = sum(sum(m.objects_by_category.values()) for m in small_grid_metrics)
    horizon = max(s.duration for s in spells)
    leave = np.zeros((1, horizon + 1))
    death = np.zeros((1, horizon + 1))
    for s in spells:
        leave[0, s.duration] += 1
        death[0, s.duration] += s.forgotten
    (r2,) = _r2_of_histograms(leave, death, np.array([mapped]), np.array([total]))
    fit = ebbinghaus_fit([s.duration for s in spells], [s.forgotten for s in spells],
                         coverage=mapped / total)  # fmt: skip
    assert r2 == pytest.approx(fit.r2, abs=1e-12)
    assert GATE_METRICS["ebbinghaus_r2"].compute(small_grid_metrics).value == fit.r2
