"""A reduced real validation run: every planted agent of both families (scout, mimic), 1
episode per spawn room (4 each), on the built-in world through the reference server, via
``emrd validate``.

Tolerances of the reduced run (4 episodes per agent instead of the full run's 80) are
stated per row below; the episodes are deterministic, so so are the verdicts. One row is
left to the full run: with 4 episodes the exponential fit of ``scout-decay-3`` (R^2 0.93) is
too noisy to sit 0.1 above ``scout-window-5`` (0.84); over 80 it does (0.96 vs 0.84).
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from pytest_emrd.cli import main

pytestmark = pytest.mark.slow

#: Reduced-run tolerance on the Ebbinghaus EFC (the full run uses 25 %).
EFC_TOLERANCE = 0.4


def _validate(out: Path) -> None:
    code = main(["validate", "--episodes", "1", "--out", str(out), "--jobs", "2",
                 "--family", "scout", "--family", "mimic"])  # fmt: skip
    (out / "exit-code").write_text(str(code))


@pytest.fixture(scope="module")
def rows(shared_folder) -> dict[str, dict]:
    """The checks of one reduced run, made once per session (xdist workers share it)."""
    out: Path = shared_folder("validation", _validate)
    code = int((out / "exit-code").read_text())
    report = json.loads((out / "validation.json").read_text())
    assert (out / "validation.md").read_text().startswith(f"{len(report['checks'])} checks")
    assert code == (1 if any(c["verdict"] == "fail" for c in report["checks"]) else 0)
    assert report["episodes"] == 1
    return {c["name"]: c for c in report["checks"]}


@pytest.mark.parametrize("mean", [3, 8, 20])
def test_ebbinghaus_recovers_the_planted_mean(rows, mean: int) -> None:
    efc = rows[f"Ebbinghaus EFC, scout-decay-{mean}"]["data"]
    assert abs(efc["efc"] - mean) / mean <= EFC_TOLERANCE
    assert rows[f"Ebbinghaus R^2, scout-decay-{mean}"]["data"]["r2"] >= 0.8


@pytest.mark.parametrize(
    "name",
    [
        "AEC vs fraction shown, scout",
        "AEC, scout: low_light vs baseline",
        "TE, scout: low_light vs baseline",
        "Miller inflection, scout-window-5",
        "Miller inflection, scout-window-10",
        "Miller inflection, scout-window-20",
        "Miller forgetting, scout (perfect memory)",
        "Serial position, scout-serial",
        "Serial position, scout-window-5",
        "Serial position, scout-window-10",
        "Serial position, scout-window-20",
        "Never-Visited, scout",
        "FPSG local, scout",
        "Never-Visited, prior",
        "Any-Bias, prior",
        "FPSG global, prior",
        "Inventory-Free chi-square",
        "Inventory-Free Cramer's V",
        "AEC and SIR, mimic: own frame vs spawn frame",
        "AEC, PA, SIR with hallucinations, mimic-h0.1",
        "Hallucinated entries per step, mimic-h0.1",
        "AEC with duplicates, mimic-p0.5: Eq. AEC",
        "SIR / AEC with duplicates, mimic-p0.5",
        "Parse failures, mimic",
        "Replies read with a repair, mimic",
        "Invalid actions, mimic",
    ],
)
def test_row_passes(rows, name: str) -> None:
    assert rows[name]["verdict"] == "pass", rows[name]["note"]


@pytest.mark.parametrize("k", [10, 20])
def test_window_fits_worse_than_decay(rows, k: int) -> None:
    (fit,) = [r for n, r in rows.items() if n.startswith(f"Exponential fit, scout-window-{k} ")]
    assert fit["verdict"] == "pass", fit["note"]


def test_paper_serial_estimator_is_biased_under_perfect_memory(rows) -> None:
    row = rows["Serial position, Eq. SPE under perfect memory (scout)"]
    assert row["verdict"] == "finding", row["note"]
    assert row["data"]["paper_early"] > row["data"]["paper_late"]
