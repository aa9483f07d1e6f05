"""``compare_runs``: paired by spec, paired bootstrap, Holm across metrics, a verdict column."""

from __future__ import annotations

import dataclasses

import pytest
from statsmodels.stats.multitest import multipletests

from pytest_emrd.metrics import GATE_METRICS
from pytest_emrd.metrics.synthetic import synthetic_grid
from pytest_emrd.report import (
    COMPARED,
    Comparison,
    compare_lines,
    compare_runs,
    render_comparison,
)
from pytest_emrd.report._document import num
from pytest_emrd.trajectory import Trajectory


@pytest.fixture(scope="module")
def forgetful() -> list[Trajectory]:
    """Same episodes as ``base`` but a planted mean memory of 3 steps instead of 10."""
    return synthetic_grid(model="syn", episodes=4, max_steps=30, mean_memory=3.0)


@pytest.fixture(scope="module")
def base(other_seeds) -> list[Trajectory]:
    """3 conditions x 4 spawns x 4 episodes: 16 pairs per cell (8 pairs cannot reach
    p < 0.05 / 33 in an exact sign-flip test: its smallest p is 2 / 2^8)."""
    return other_seeds[0]


@pytest.fixture(scope="module")
def other_seeds() -> tuple[list[Trajectory], list[Trajectory]]:
    """The same agent (planted memory 10 steps) run twice with different agent seeds."""
    return (
        synthetic_grid(model="syn", episodes=4, max_steps=30, seed=0),
        synthetic_grid(model="syn", episodes=4, max_steps=30, seed=1),
    )


def renamed(trajectories: list[Trajectory], model: str) -> list[Trajectory]:
    return [dataclasses.replace(t, spec=dataclasses.replace(t.spec, model=model))
            for t in trajectories]  # fmt: skip


def test_every_compared_metric_is_a_gate_metric() -> None:
    assert set(COMPARED) <= set(GATE_METRICS)


def test_a_run_against_itself_changes_nothing(grid: list[Trajectory]) -> None:
    c = compare_runs(grid, grid)
    assert len(c.differences) == 3 * len(COMPARED) and not c.only_a and not c.only_b
    for d in c.differences:
        if d.diff is not None:
            assert d.diff == 0.0
        if d.p_value is not None:
            assert d.p_value == 1.0 and d.p_holm == 1.0 and d.ci_low == d.ci_high == 0.0
            assert d.verdict == "no change" and d.significant is False


def test_the_same_agent_on_other_seeds_is_not_significant(other_seeds) -> None:
    """Same planted cognition, different realisations: the null is true in every test."""
    a, b = other_seeds
    c = compare_runs(a, b)
    tested = [d for d in c.differences if d.p_value is not None]
    assert len(tested) >= 30
    quiet = ("no change", "inconclusive")  # inconclusive: too few pairs define the metric
    assert all(d.verdict in quiet for d in tested), [
        (d.condition, d.metric, d.p_value, d.p_holm) for d in tested if d.verdict not in quiet
    ]


def test_holm_is_statsmodels_over_every_test_of_the_comparison(other_seeds) -> None:
    c = compare_runs(*other_seeds)
    tested = [d for d in c.differences if d.p_value is not None]
    expected = multipletests([d.p_value for d in tested], method="holm")[1]
    assert [d.p_holm for d in tested] == pytest.approx(list(expected))
    assert all(d.p_holm >= d.p_value for d in tested)


def test_planted_forgetting_is_worse_memory_strength(base, forgetful) -> None:
    c = compare_runs(base, forgetful)
    strength = [d for d in c.differences if d.metric == "memory_strength"]
    assert len(strength) == 3
    for d in strength:
        assert d.diff is not None and d.diff < 0 and d.ci_high < 0
        assert d.verdict == "worse" and d.significant is True
    for d in c.differences:
        if d.ci_low is not None:
            assert d.ci_low <= d.diff <= d.ci_high, d


def test_swapping_sides_swaps_better_and_worse(base, forgetful) -> None:
    forward = compare_runs(base, forgetful)
    backward = compare_runs(forgetful, base)
    flip = {
        "better": "worse",
        "worse": "better",
        "no change": "no change",
        "n/a": "n/a",
        "inconclusive": "inconclusive",
    }
    assert [flip[d.verdict] for d in forward.differences] == [
        d.verdict for d in backward.differences
    ]
    assert {d.verdict for d in backward.differences if d.metric == "memory_strength"} == {"better"}


@pytest.mark.parametrize("metric", ["te", "never_visited", "any_bias", "parse_failure_rate"])
def test_lower_is_better_metrics_read_a_drop_as_better(metric: str) -> None:
    assert GATE_METRICS[metric].better == "lower"


def test_values_are_the_gate_metrics_over_the_pairs(base, forgetful) -> None:
    c = compare_runs(base, forgetful)
    for d in c.differences:
        if d.metric in ("aec", "te", "pa", "memory_strength", "errored_rate"):  # defined in all
            cell_a = [t for t in base if t.spec.condition == d.condition]
            expected = GATE_METRICS[d.metric].compute(cell_a)
            assert (d.a.value, d.a.n) == (pytest.approx(expected.value), expected.n)
        if d.diff is not None:
            assert d.diff == pytest.approx(d.b.value - d.a.value)


def test_episodes_pair_by_spawn_and_episode_only(grid: list[Trajectory]) -> None:
    b = [t for t in grid if not (t.spec.spawn == "office" and t.spec.episode == 1)]
    c = compare_runs(grid, b)
    aec = [d for d in c.differences if d.metric == "aec"]
    assert {d.unpaired for d in aec} == {1} and {d.a.n for d in aec} == {7}
    shifted = [dataclasses.replace(t, spec=dataclasses.replace(t.spec, episode=9)) for t in grid]
    none = compare_runs(grid, shifted)
    assert {d.verdict for d in none.differences} == {"n/a"}
    assert none.differences[0].reason.startswith("no paired episodes")


def test_two_pairs_are_never_significant(grid, forgetful) -> None:
    """Two pairs with the same sign: a bootstrap p would be ~0; the exact sign-flip p is 0.5."""

    def two(ts: list[Trajectory]) -> list[Trajectory]:
        return [t for t in ts if t.spec.condition == "baseline" and t.spec.spawn == "office"]

    strength = next(d for d in compare_runs(two(grid), two(forgetful)).differences
                    if d.metric == "memory_strength")  # fmt: skip
    assert strength.diff < 0 and strength.ci_high < 0
    assert strength.p_value == 0.5 and strength.verdict == "inconclusive"


def _steps_plus(trajectories: list[Trajectory], extra: int) -> list[Trajectory]:
    """Each episode with its last ``extra`` steps repeated: the same world, more steps."""
    return [dataclasses.replace(t, steps=(*t.steps, *t.steps[-extra:])) for t in trajectories]


def test_eight_pairs_that_all_moved_say_inconclusive(grid: list[Trajectory]) -> None:
    """+3 steps in every one of 8 pairs: the exact sign-flip p is 2/2^8 at best, and Holm
    over the comparison's tests pushes it past 0.05: "inconclusive", never "no change"."""
    baseline = [t for t in grid if t.spec.condition == "baseline"]
    c = compare_runs(baseline, _steps_plus(baseline, 3))
    te = next(d for d in c.differences if d.metric == "te")
    tested = sum(d.p_value is not None for d in c.differences)
    assert te.pairs == 8 and te.diff is not None and te.diff != 0
    assert te.p_reachable == pytest.approx(min(1.0, tested * 2 / 2**8))
    assert te.p_reachable >= 0.05 and te.verdict == "inconclusive"
    assert te.reason == (f"8 pairs cannot reach Holm p < 0.05: the smallest reachable is "
                         f"{te.p_reachable:.3g}; more episodes per cell can")  # fmt: skip
    assert not any(d.verdict == "no change" for d in c.differences if d.diff)
    md = render_comparison(c, ["md"])["compare.md"].decode()
    assert "**inconclusive**" in md and "8 pairs cannot reach Holm p < 0.05" in md


def test_enough_pairs_can_say_no_change(other_seeds) -> None:
    """16 pairs per cell can reach significance: a null result there reads "no change"."""
    c = compare_runs(*other_seeds)
    tested = [d for d in c.differences if d.p_value is not None and d.pairs >= 16]
    assert tested and all(d.p_reachable < 0.05 for d in tested)
    assert {d.verdict for d in tested} == {"no change"}


def test_undefined_metrics_say_why(grid, as_errored) -> None:
    """SIR undefined in every episode, none errored: the metric's own reason, not "no
    non-errored episode"; every pair errored: that, in those words."""
    from pytest_emrd.metrics import as_episode_metrics

    baseline = [t for t in grid if t.spec.condition == "baseline"]
    why = "no room was re-entered"
    no_sir = [dataclasses.replace(m, sir=None, reasons={**m.reasons, "sir": why})
              for m in as_episode_metrics(baseline)]  # fmt: skip
    sir = next(d for d in compare_runs(no_sir, no_sir).differences if d.metric == "sir")
    assert sir.verdict == "n/a" and sir.reason == f"undefined in every pair: {why}"
    broken = [as_errored(t) for t in baseline]
    aec = next(d for d in compare_runs(baseline, broken).differences if d.metric == "aec")
    assert aec.verdict == "n/a" and aec.reason == "every pair holds an errored episode"


def test_seeded_and_reproducible(grid, forgetful) -> None:
    assert compare_runs(grid, forgetful) == compare_runs(grid, forgetful)
    assert compare_runs(grid, forgetful, rng_seed=1).rng_seed == 1


def test_resamples_grow_with_the_number_of_tests(grid) -> None:
    c = compare_runs(grid, grid)
    assert c.n_resamples >= 10 * len(c.differences) / c.alpha


def test_cells_in_one_run_only_are_listed(grid: list[Trajectory]) -> None:
    baseline = [t for t in grid if t.spec.condition == "baseline"]
    c = compare_runs(grid, baseline)
    assert c.only_a == ("syn/default/low_light", "syn/default/texture") and c.only_b == ()
    assert {d.condition for d in c.differences} == {"baseline"}


def test_one_pair_gives_a_diff_without_a_test(grid: list[Trajectory]) -> None:
    one = grid[:1]
    aec = next(d for d in compare_runs(one, one).differences if d.metric == "aec")
    assert aec.diff == 0.0 and aec.ci_low is None and aec.verdict == "n/a"
    assert aec.reason == "fewer than two pairs: no test"


def test_two_models_of_one_run(base, forgetful) -> None:
    run = base + renamed(forgetful, "syn-candidate")
    c = compare_runs(run, run, models=("syn", "syn-candidate"))
    assert {(d.model, d.model_b) for d in c.differences} == {("syn", "syn-candidate")}
    assert {d.verdict for d in c.differences if d.metric == "memory_strength"} == {"worse"}
    same = compare_runs(run, base + renamed(base, "syn-copy"), models=("syn", "syn"))
    assert {d.verdict for d in same.differences} <= {"no change", "n/a"}
    md = render_comparison(c, ["md"])["compare.md"].decode()
    assert "A = model syn of A, B = model syn-candidate of B" in md
    assert "*syn vs syn-candidate, Baseline*" in md


def test_never_minus_zero() -> None:
    assert num(-1e-9) == "0.000" and num(-0.0) == "0.000" and num(-0.0004) == "0.000"
    assert num(-0.0006) == "-0.001" and num(0.0) == "0.000"


def test_comparison_renders_and_round_trips(base, forgetful) -> None:
    c = compare_runs(base, forgetful, names=("v1", "v2"))
    assert Comparison.from_dict(c.to_dict()) == c
    files = render_comparison(c)
    md = files["compare.md"].decode()
    assert "A = v1, B = v2" in md and "| memory_strength | higher |" in md
    assert "**worse**" in md and "-0.000" not in md
    assert "Holm-corrected across all" in md
    assert set(files) == {"compare.md", "compare.html", "compare.json"}


def test_faster_but_covering_less_is_flagged_not_better(base) -> None:
    quit_early = [dataclasses.replace(t, steps=t.steps[:4]) for t in base]
    lines = compare_lines(compare_runs(base, quit_early))
    te = next(line for line in lines if line.startswith("syn baseline te:"))
    aec = next(line for line in lines if line.startswith("syn baseline aec:"))
    assert aec.endswith(": worse")
    assert ": flagged (fewer actions but AEC fell by" in te


def test_one_terminal_line_per_metric_and_cell(base, forgetful) -> None:
    comparison = compare_runs(base, forgetful)
    lines = compare_lines(comparison)
    assert len(lines) == len(comparison.differences)
    strength = next(line for line in lines if line.startswith("syn baseline memory_strength:"))
    assert strength.endswith(": worse") and "B - A -" in strength and "Holm p" in strength
