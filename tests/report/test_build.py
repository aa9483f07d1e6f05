"""The report's numbers are the metrics library's numbers for the same episodes."""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np
import pytest

from pytest_emrd import metrics
from pytest_emrd.report import Report, build_report, group_cells, row_label
from pytest_emrd.trajectory import Trajectory


@pytest.fixture(scope="module")
def report(variant_grid: list[Trajectory], embed: Callable[[Sequence[str]], np.ndarray]) -> Report:
    return build_report(variant_grid, embed=embed)


def _cell(trajs: list[Trajectory], model: str, variant: str, condition: str) -> list[Trajectory]:
    return sorted(
        (t for t in trajs if (t.spec.model, t.spec.variant, t.spec.condition)
         == (model, variant, condition)),
        key=lambda t: t.spec.case_id,
    )  # fmt: skip


def test_every_cell_is_a_row_in_paper_order(report: Report) -> None:
    keys = [(r.model, r.variant, r.condition) for r in report.exploration]
    assert keys == [
        ("syn", "default", "baseline"),
        ("syn", "default", "low_light"),
        ("syn", "default", "texture"),
        ("syn", "B3", "baseline"),
        ("syn", "no_inventory", "baseline"),
    ]
    for rows in (report.focal, report.fpsg, report.ebbinghaus, report.serial_position,
                 report.tbs, report.miller, report.sir):  # fmt: skip
        assert [(r.model, r.variant, r.condition) for r in rows] == keys


def test_tables_equal_the_metrics_library(report: Report, variant_grid: list[Trajectory]) -> None:
    for row in report.exploration:
        cell = _cell(variant_grid, row.model, row.variant, row.condition)
        assert row.aec == metrics.GATE_METRICS["aec"].compute(cell)
        assert row.te == metrics.GATE_METRICS["te"].compute(cell)
        aec = [metrics.episode_metrics(t).aec for t in cell]
        assert row.aec_sd == pytest.approx(np.std(aec, ddof=1))
    for f, p, e, s in zip(report.focal, report.fpsg, report.ebbinghaus, report.serial_position,
                          strict=True):  # fmt: skip
        cell = _cell(variant_grid, f.model, f.variant, f.condition)
        assert f.distribution == metrics.focal_distribution(cell)
        assert f.consensus == metrics.consensus(cell)
        assert p.summary == metrics.fpsg(cell)
        assert e.fit == metrics.ebbinghaus(cell)
        assert s.spe == metrics.serial_position(cell)
    default = sorted(
        (t for t in variant_grid if t.spec.variant == "default"), key=lambda t: t.spec.case_id
    )
    assert report.anova[0].anova == metrics.anova_conditions(default)


def test_figures_equal_the_metrics_library(report: Report, variant_grid: list[Trajectory]) -> None:
    for tbs, miller, sir in zip(report.tbs, report.miller, report.sir, strict=True):
        cell = _cell(variant_grid, tbs.model, tbs.variant, tbs.condition)
        assert tbs.curve == metrics.tbs_curve(cell)
        assert miller.curve == metrics.miller_curve(cell)
        assert sir.sir == metrics.spatial_identity_resolution(cell)
    for km in report.km:
        cell = _cell(variant_grid, km.model, km.variant, km.condition)
        assert km.km == metrics.kaplan_meier_anchored(cell)[km.category]
        assert km.fit == metrics.ebbinghaus(cell).by_category[km.category]
    for pa in report.pa:
        cell = [t for t in _cell(variant_grid, pa.model, pa.variant, pa.condition)
                if t.spec.spawn == pa.spawn]  # fmt: skip
        assert pa.values == tuple(v for v in metrics.positional_accuracy(cell) if v is not None)


def test_interventions_use_the_library_tests(report: Report, variant_grid) -> None:
    (table,) = report.interventions
    assert (table.model, table.condition) == ("syn", "baseline")
    default = metrics.focal_distribution(_cell(variant_grid, "syn", "default", "baseline"))
    assert table.reference == default.overall
    assert [v.variant for v in table.variants] == ["B3", "no_inventory"]
    b3 = metrics.focal_distribution(_cell(variant_grid, "syn", "B3", "baseline")).overall
    ref_c, b3_c = default.overall.counts, b3.counts
    split = [[ref_c["C"], default.overall.n - ref_c["C"]], [b3_c["C"], b3.n - b3_c["C"]]]
    assert table.variants[0].fisher == metrics.fisher_exact_2x2(split)
    full = [[ref_c[c] for c in "COKEX"], [b3_c[c] for c in "COKEX"]]
    assert table.variants[0].chi_square == metrics.chi_square(full)
    assert table.variants[0].cramers_v == metrics.cramers_v(full)
    assert table.overall == metrics.chi_square(split)
    assert table.overall_variants == ("default", "B3")


def test_reasoning_per_model_row_uses_the_given_encoder(report: Report, variant_grid, embed):
    rows = {r.model: r.representative for r in report.reasoning.rows}
    assert set(rows) == {"syn", "syn [B3]", "syn [no_inventory]"}
    default = [t.rationale for t in variant_grid if t.spec.variant == "default"]
    ordered = sorted(
        (t for t in variant_grid if t.spec.variant == "default"), key=lambda t: t.spec.case_id
    )
    assert rows["syn"] == metrics.representative_reasoning(
        [t.rationale for t in ordered], embed=embed
    )
    assert rows["syn"].n == sum(r is not None for r in default)


def test_episode_map_is_the_aligned_terminal_map(report: Report, variant_grid) -> None:
    m = report.episode_map
    assert m is not None
    traj = next(t for t in variant_grid if t.spec.case_id == m.case_id)
    assert traj.spec.condition == "baseline"
    assert len(m.path) == len(traj.steps)
    matching = metrics.match_map(traj.final_map, traj.ground_truth.objects)
    assert {e.object_id for e in m.entries} - {None} == set(matching.object_ids)
    truth = {o.object_id: o for o in traj.ground_truth.objects}
    # noise is 0.3 m: after alignment matched entries sit near their objects
    errors = [np.hypot(e.x - truth[e.object_id].x, e.z - truth[e.object_id].z)
              for e in m.entries if e.object_id]  # fmt: skip
    assert m.rmse == pytest.approx(np.sqrt(np.mean(np.square(errors))))
    assert m.rmse < 1.0


def test_report_round_trips_through_its_dict(report: Report) -> None:
    assert Report.from_dict(report.to_dict()) == report


def test_group_cells_and_row_labels(variant_grid: list[Trajectory]) -> None:
    cells = group_cells(metrics.as_episode_metrics(variant_grid))
    assert sum(map(len, cells.values())) == len(variant_grid)
    assert all(
        [m.spec.case_id for m in ems] == sorted(m.spec.case_id for m in ems)
        for ems in cells.values()
    )
    assert row_label("gemini", "default") == "gemini"
    assert row_label("gemini", "B3") == "gemini [B3]"


def test_a_stored_run_is_reported_from_its_heads_decoding_only_the_map_episode(
    tmp_path, grid: list[Trajectory]
) -> None:
    from pytest_emrd.cassette import EpisodeRun
    from pytest_emrd.run import ResultsStore, load_run_episodes

    store = ResultsStore(tmp_path, session="s", protocol=grid[0].protocol)
    for t in grid:
        store.get_or_compute(t.spec, lambda spec, t=t: EpisodeRun(t, False, 0, 0.0))
    episodes = load_run_episodes([tmp_path])
    measured = metrics.as_episode_metrics(grid)
    from_heads = build_report(episodes, episode_metrics=measured, with_reasoning=False)
    decoded = [e.head.spec.case_id for e in episodes if "trajectory" in e.__dict__]
    assert from_heads.episode_map is not None and decoded == [from_heads.episode_map.case_id]
    assert from_heads == build_report(grid, episode_metrics=measured, with_reasoning=False)
