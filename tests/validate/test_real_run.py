"""A reduced real validation run: every planted agent, 1 episode per spawn room (4 each),
on the built-in world through the reference server, via ``emrd validate``.

Tolerances of the reduced run (4 episodes per agent instead of the full run's 80) are
stated per row below; the episodes are deterministic, so so are the verdicts. Rows that
fail for a known reason in a reference agent or a metric are strict xfails naming it, so
fixing the cause turns them into errors until the marker is removed. The TE row (low
light raises TE) is left to the full run: over 80 paired episodes the scout's TE falls in
low light (it stops when it sees no doorway), while these 4 happen to rise.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from pytest_emrd.cli import main

pytestmark = pytest.mark.slow

#: Reduced-run tolerance on the Ebbinghaus EFC (the full run uses 25 %).
EFC_TOLERANCE = 0.4


@pytest.fixture(scope="module")
def rows(tmp_path_factory: pytest.TempPathFactory) -> dict[str, dict]:
    out: Path = tmp_path_factory.mktemp("validation")
    code = main(["validate", "--episodes", "1", "--out", str(out), "--jobs", "2"])
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
        "AEC vs discoverable fraction, scout",
        "AEC, scout: low_light vs baseline",
        "Miller inflection, scout-window-10",
        "Miller inflection, scout-window-20",
        "Miller forgetting, scout (perfect memory)",
        "Never-Visited, scout",
        "FPSG local, scout",
        "Never-Visited, prior",
        "Inventory-Free chi-square",
        "Inventory-Free Cramer's V",
    ],
)
def test_row_passes(rows, name: str) -> None:
    assert rows[name]["verdict"] == "pass", rows[name]["note"]


def test_window_fits_worse_than_decay(rows) -> None:
    fits = [r for n, r in rows.items() if n.startswith("Exponential fit, scout-window")]
    assert len(fits) == 3
    assert all(r["verdict"] == "pass" for r in fits), [r["note"] for r in fits]


@pytest.mark.parametrize(
    "name",
    [
        pytest.param(
            "Miller inflection, scout-window-5",
            marks=pytest.mark.xfail(
                strict=True, reason="metric: k <= w puts every load in bin 1, no inflection"
            ),
        ),
        pytest.param(
            "Serial position, scout-serial",
            marks=pytest.mark.xfail(
                strict=True,
                reason="agent thirds are relative to the running count; metric "
                "averages censored TTF, biasing the late third low",
            ),
        ),
        pytest.param(
            "Any-Bias, prior",
            marks=pytest.mark.xfail(
                strict=True, reason="agent: prior maps chosen-room objects seen through doorways"
            ),
        ),
    ],
)
def test_known_failure(rows, name: str) -> None:
    assert rows[name]["verdict"] == "pass", rows[name]["note"]
