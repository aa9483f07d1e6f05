"""A report from real episodes: reference agents on the builtin world over the local server."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from pytest_emrd import metrics
from pytest_emrd.cli import main
from pytest_emrd.episode import run_episode
from pytest_emrd.report import FIGURES
from pytest_emrd.trajectory import EpisodeSpec, Trajectory


@pytest.fixture(scope="module")
def recorded() -> list[Trajectory]:
    """scout and scout-decay-4, baseline and low light, two spawn rooms (8 episodes), and one
    scout episode on a generated office where it re-enters a room (SIR; the scout never
    re-enters a room of the paper's office): its own report row, ``scout@generated``."""
    return [
        *(
            run_episode(EpisodeSpec(model, condition, spawn, 0, modality="text"))
            for model in ("scout", "scout-decay-4")
            for condition in ("baseline", "low_light")
            for spawn in ("office", "entrance")
        ),
        run_episode(
            EpisodeSpec("scout", "low_light", "office", 0, modality="text", layouts="generated")
        ),
    ]


@pytest.mark.slow
def test_report_of_a_small_recorded_run(recorded, make_run_dir, tmp_path: Path) -> None:
    assert all(t.status != "errored" for t in recorded), [t.error for t in recorded]
    run = make_run_dir("run", recorded)
    out = tmp_path / "report"
    assert main(["report", str(run), "--out", str(out), "--thresholds",
                 str(Path(__file__).parents[2] / "thresholds.yaml")]) == 0  # fmt: skip
    written = {p.name for p in out.iterdir()}
    assert written >= {"report.md", "report.html", "report.json"}
    md = (out / "report.md").read_text()
    # a figure without data is left out and the report says why (no scout re-enters a room)
    assert written >= {f.name for f in FIGURES} - {"sir.png"}
    assert "sir.png" in written or "no episode re-entered a room with mapped objects" in md
    data = json.loads((out / "report.json").read_text())
    by_key = {(r["model"], r["condition"]): r for r in data["exploration"]}
    for model in ("scout", "scout-decay-4"):
        for condition in ("baseline", "low_light"):
            key = (model, condition, "paper")
            cell = sorted((t for t in recorded
                           if (t.spec.model, t.spec.condition, t.spec.layouts) == key),
                          key=lambda t: t.spec.case_id)  # fmt: skip
            expected = metrics.GATE_METRICS["aec"].compute(cell)
            assert by_key[(model, condition)]["aec"]["value"] == expected.value
    assert data["gates"]["verdicts"], "thresholds.yaml gates the scout reference agent"
    assert "## Gates" in md and "| scout |" in md
    assert ("scout@generated", "low_light") in by_key, "generated layouts are their own row"
