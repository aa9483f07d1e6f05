"""Spells, time-to-forget, anchored KM, Ebbinghaus, serial position, Miller, SIR, ANOVA."""

from __future__ import annotations

import math
from collections.abc import Callable

import pytest
from hypothesis import given
from hypothesis import strategies as st
from scipy import stats

from pytest_emrd.errors import ConfigError
from pytest_emrd.metrics import (
    EpisodeMetrics,
    anova_conditions,
    ebbinghaus,
    episode_metrics,
    forgetting_spells,
    kaplan_meier_anchored,
    miller_curve,
    serial_position,
    spatial_identity_resolution,
    time_to_forget,
)
from pytest_emrd.rooms import OFFICE
from pytest_emrd.trajectory import GroundTruthObject, Trajectory

MakeObj = Callable[..., GroundTruthObject]
MakeTraj = Callable[..., Trajectory]


def test_spell_event_and_both_kinds_of_censoring(make_obj: MakeObj, make_traj: MakeTraj) -> None:
    # spacings 3, 5, 7: any two laptops of the map fix which ones they are (no anchor needed)
    truth = [make_obj(f"Laptop_{i}", x=float(i * i), category="clutter") for i in (1, 2, 3, 4)]
    held = {f"l{i}": ("Laptop", float(i * i), 0.0) for i in (1, 2, 3)}
    steps = [
        (OFFICE, ["Laptop_1", "Laptop_2", "Laptop_3"], held),
        (OFFICE, [], {**held, "l4": ("Laptop", 16.0, 0.0)}),  # Laptop_4 mapped unseen: no spell
        (OFFICE, ["Laptop_2"], {k: v for k, v in held.items() if k != "l1"}),
    ]
    spells = {s.object_id: s for s in episode_metrics(make_traj(truth, steps)).spells}
    assert set(spells) == {"Laptop_1", "Laptop_2", "Laptop_3"}
    assert (spells["Laptop_1"].duration, spells["Laptop_1"].forgotten) == (2, True)
    assert (spells["Laptop_2"].duration, spells["Laptop_2"].forgotten) == (1, False)  # seen again
    assert (spells["Laptop_3"].duration, spells["Laptop_3"].forgotten) == (2, False)  # episode end
    assert [spells[f"Laptop_{i}"].discovery_rank for i in (1, 2, 3)] == [1, 2, 3]


def _laptop_episode(make_obj: MakeObj, make_traj: MakeTraj) -> Trajectory:
    """Appendix B's KM example as an episode: 50 laptops, 30 mapped, 3/2/5 forgotten."""
    truth = [make_obj(f"Laptop_{i}", x=float(i), category="clutter") for i in range(1, 51)]
    mapped = {f"Laptop_{i}": ("Laptop", float(i), 0.0) for i in range(1, 31)}
    ids = list(mapped)
    keep_2, keep_3, keep_4 = ids[3:], ids[5:], ids[10:]
    steps = [
        (OFFICE, ids, mapped),
        (OFFICE, [], {k: mapped[k] for k in keep_2}),
        (OFFICE, [], {k: mapped[k] for k in keep_3}),
        (OFFICE, [], {k: mapped[k] for k in keep_4}),
    ]
    return make_traj(truth, steps)


def test_km_laptop_example_from_an_episode(make_obj: MakeObj, make_traj: MakeTraj) -> None:
    km = kaplan_meier_anchored([_laptop_episode(make_obj, make_traj)])["clutter"]
    assert km.coverage == pytest.approx(0.6)
    assert km.survival[1:] == pytest.approx((0.54, 0.50, 0.40), abs=1e-12)


def test_time_to_forget_and_ebbinghaus_of_the_laptop_episode(
    make_obj: MakeObj, make_traj: MakeTraj
) -> None:
    traj = _laptop_episode(make_obj, make_traj)
    ttf = time_to_forget([traj])
    assert (len(ttf.spells), ttf.events) == (30, 10)
    # EFC = (3*1 + 2*2 + 5*3 + 20*3) / 10 = 8.2
    eb = ebbinghaus([traj])
    assert eb.by_category["clutter"].efc == pytest.approx(8.2)
    assert eb.pooled.efc == pytest.approx(8.2)
    assert eb.pooled.coverage == pytest.approx(0.6)
    assert sorted(forgetting_spells([traj]), key=lambda s: s.object_id) == sorted(
        ttf.spells, key=lambda s: s.object_id
    )
    # discovered at the same step: ranked in the order the map lists them, not by id string
    assert [s.object_id for s in ttf.spells[:3]] == ["Laptop_1", "Laptop_2", "Laptop_3"]


def test_no_forgetting_gives_unbounded_strength_not_a_crash(
    make_obj: MakeObj, make_traj: MakeTraj
) -> None:
    truth = [make_obj("Desk_1")]
    traj = make_traj(truth, [(OFFICE, ["Desk_1"], {"d": ("Desk", 0.0, 0.0)}),
                             (OFFICE, [], {"d": ("Desk", 0.0, 0.0)})])  # fmt: skip
    eb = ebbinghaus([traj])
    assert eb.pooled.efc == math.inf and "unbounded" in (eb.pooled.reason or "")
    m = episode_metrics(traj)
    assert m.memory_strength == math.inf and "unbounded" in m.reasons["memory_strength"]


def test_remember_aggregates_handle_no_episodes() -> None:
    assert kaplan_meier_anchored([]) == {}
    assert ebbinghaus([]).pooled.efc is None
    assert serial_position([]).early is None
    assert miller_curve([]).reason == "no step with a non-empty map"
    assert spatial_identity_resolution([]).mean is None
    assert time_to_forget([]).mean_observed is None
    assert anova_conditions([]).statistic is None


def _miller_episodes(make_traj: MakeTraj, plan: list[tuple[int, int, int]]) -> list[Trajectory]:
    """Two-step episodes: ``(load, steps, forgets)`` -> episodes with that load."""
    episodes = []
    for load, steps, forgets in plan:
        labels = {f"o{i}": ("Thing", float(i), 0.0) for i in range(load)}
        for k in range(steps):
            after = dict(list(labels.items())[1:]) if k < forgets else labels
            episodes.append(make_traj([], [(OFFICE, [], labels), (OFFICE, [], after)]))
    return episodes


def test_miller_appendix_b_example(make_traj: MakeTraj) -> None:
    # Loads 3, 8 and 13 fall in bins 1, 2, 3: 1/20 = 0.05, 2/25 = 0.08, 13/20 = 0.65.
    curve = miller_curve(_miller_episodes(make_traj, [(3, 20, 1), (8, 25, 2), (13, 20, 13)]))
    assert curve.bins == (1, 2, 3)
    assert curve.probabilities == pytest.approx((0.05, 0.08, 0.65))
    assert (curve.b_star, curve.m_star) == (3, 15)


@pytest.mark.parametrize(
    ("plan", "min_steps", "reason_part"),
    [
        ([(3, 4, 0), (8, 4, 0)], 1, "no rise between consecutive load bins (from ML(0) = 0)"),
        ([(3, 4, 1), (8, 4, 1)], 5, "no load bin with >= 5 steps"),
    ],
    ids=["never-forgets", "no-eligible-bin"],
)
def test_miller_without_inflection(
    make_traj: MakeTraj, plan: list[tuple[int, int, int]], min_steps: int, reason_part: str
) -> None:
    curve = miller_curve(_miller_episodes(make_traj, plan), min_steps=min_steps)
    assert curve.b_star is None and curve.m_star is None
    assert curve.reason is not None and reason_part in curve.reason


@pytest.mark.parametrize(
    ("plan", "b_star"),
    [
        ([(3, 8, 7)], 1),  # capacity <= w: every load in bin 1, rise 0.875 from the anchor
        ([(3, 4, 2), (8, 4, 1)], 1),  # 0.5 then 0.25: the only rise is the one into bin 1
        ([(3, 10, 4), (8, 10, 9)], 2),  # 0.4 from the anchor, then 0.5: bin 2
        ([(13, 5, 5)], 3),  # first populated bin 3: measured from ML(0) = 0
    ],
    ids=["single-bin", "falling", "later-rise-wins", "first-bin-three"],
)
def test_miller_first_bin_rises_from_the_anchor(
    make_traj: MakeTraj, plan: list[tuple[int, int, int]], b_star: int
) -> None:
    curve = miller_curve(_miller_episodes(make_traj, plan))
    assert (curve.b_star, curve.m_star, curve.reason) == (b_star, 5 * b_star, None)


def test_miller_min_steps_keeps_sparse_bins_out_of_the_inflection(make_traj: MakeTraj) -> None:
    episodes = _miller_episodes(make_traj, [(3, 10, 1), (8, 10, 5), (13, 1, 1)])
    assert miller_curve(episodes).b_star == 3
    assert miller_curve(episodes, min_steps=5).b_star == 2


@pytest.mark.parametrize(
    "kwargs", [{"width": 0}, {"min_steps": 0}, {"width": 2.5}], ids=["w0", "min0", "w-float"]
)
def test_miller_bad_arguments(kwargs: dict[str, float]) -> None:
    with pytest.raises(ConfigError):
        miller_curve([], **kwargs)  # type: ignore[arg-type]


def test_miller_probabilities_in_unit_interval(small_grid_metrics: list[EpisodeMetrics]) -> None:
    curve = miller_curve(small_grid_metrics)
    assert all(0.0 <= p <= 1.0 for p in curve.probabilities)
    assert sum(curve.steps) == sum(len(m.miller_loads) for m in small_grid_metrics)


@given(st.lists(st.tuples(st.integers(1, 20), st.integers(1, 5), st.integers(0, 5)), max_size=5))
def test_miller_probabilities_property(
    make_traj: MakeTraj, plan: list[tuple[int, int, int]]
) -> None:
    curve = miller_curve(_miller_episodes(make_traj, [(a, b, min(c, b)) for a, b, c in plan]))
    assert all(0.0 <= p <= 1.0 for p in curve.probabilities)
    assert all(not math.isnan(p) for p in curve.probabilities)


def test_serial_position_aggregate_skips_undefined_bins(
    small_grid_metrics: list[EpisodeMetrics],
) -> None:
    sp = serial_position(small_grid_metrics)
    early = [m.serial_position[0] for m in small_grid_metrics if m.serial_position[0] is not None]
    assert sp.n[0] == len(early)
    assert sp.early == pytest.approx(sum(early) / len(early))


def test_planted_memory_strength_is_recovered(small_grid_metrics: list[EpisodeMetrics]) -> None:
    # synthetic.py plants geometric forgetting with mean 10 steps out of view.
    pooled = ebbinghaus(small_grid_metrics).pooled
    assert pooled.efc == pytest.approx(10.0, rel=0.15)
    assert pooled.r2 is not None and pooled.r2 > 0.9


def test_sir_aggregate_counts_undefined_episodes(small_grid_metrics: list[EpisodeMetrics]) -> None:
    sir = spatial_identity_resolution(small_grid_metrics)
    assert len(sir.values) + sum(sir.undefined.values()) == len(small_grid_metrics)
    assert all(0.0 <= v <= 1.0 for v in sir.values)


def test_anova_conditions_agrees_with_scipy(small_grid_metrics: list[EpisodeMetrics]) -> None:
    res = anova_conditions(small_grid_metrics)
    groups: dict[str, list[float]] = {}
    for m in small_grid_metrics:
        s = m.memory_strength
        if s is not None and math.isfinite(s):
            groups.setdefault(m.spec.condition, []).append(s)
    ref = stats.f_oneway(*groups.values())
    assert res.statistic == pytest.approx(ref.statistic)
    assert res.p_value == pytest.approx(ref.pvalue)
    assert set(res.groups) == {"baseline", "low_light", "texture"}


def test_discovery_counts_from_when_the_entry_was_written_not_when_the_matcher_read_it(
    make_obj: MakeObj, make_traj: MakeTraj
) -> None:
    # One chair alone fixes no frame: the matcher reads it as Chair_1 (the first by id) until
    # the desk written at step 2 shows it is Chair_2. The model mapped Chair_2 at step 1.
    truth = [
        make_obj("Chair_1", x=0.0, category="clutter"),
        make_obj("Chair_2", x=3.0, category="clutter"),
        make_obj("Desk_1", z=5.0, category="salient"),
    ]
    chair, desk = ("Chair", 13.0, 10.0), ("Desk", 10.0, 15.0)  # the model's frame: shifted
    steps = [
        (OFFICE, ["Chair_2"], {"c": chair}),
        (OFFICE, ["Chair_2", "Desk_1"], {"c": chair, "d": desk}),
        (OFFICE, [], {"c": chair, "d": desk}),
    ]
    m = episode_metrics(make_traj(truth, steps))
    ranks = {s.object_id: s.discovery_rank for s in m.spells}
    assert ranks == {"Chair_2": 1, "Desk_1": 3}  # Chair_1 (read at step 1, withdrawn) is 2nd
