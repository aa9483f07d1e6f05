"""Statistics rows: exact reproduction of the paper's tables, and exact findings."""

from __future__ import annotations

import pytest

from pytest_emrd.validate import statistics_checks


@pytest.fixture(scope="module")
def rows() -> dict:
    return {c.name: c for c in statistics_checks()}


@pytest.mark.parametrize(
    ("name", "verdict", "recovered"),
    [
        pytest.param("Inventory-Free chi-square", "pass", 62.4318, id="inventory-free-chi2"),
        pytest.param("Inventory-Free Cramer's V", "pass", 0.6266, id="inventory-free-V"),
        pytest.param("Inventory-Free p", "finding", 1.776e-13, id="inventory-free-p"),
        pytest.param("Appendix E chi-square (5 x 2)", "finding", 17.3128, id="E-chi2"),
        pytest.param("Appendix E df", "pass", 4.0, id="E-df"),
        pytest.param("Appendix E p (chi-square)", "finding", 0.0016803, id="E-p"),
        pytest.param("Appendix E Fisher p, B1", "finding", 0.42566, id="E-B1"),
        pytest.param("Appendix E Fisher p, B2", "finding", 0.52328, id="E-B2"),
        pytest.param("Appendix E Fisher p, B3", "finding", 0.010143, id="E-B3"),
        pytest.param("Appendix E Fisher p, B4", "finding", 0.18639, id="E-B4"),
        pytest.param("Appendix E Fisher p, Neutral", "finding", 0.60265, id="E-neutral"),
        pytest.param("Appendix F spawn-room share (%)", "pass", 100 * 41 / 81, id="F-share"),
        pytest.param("Appendix F totals vs Inventory-Free table", "finding", 81, id="F-totals"),
    ],
)
def test_statistics_row(rows: dict, name: str, verdict: str, recovered: float) -> None:
    row = rows[name]
    assert row.verdict == verdict, row.note
    assert row.data["recovered"] == pytest.approx(recovered, rel=1e-4)


def test_appendix_e_names_the_counts_that_reproduce_every_printed_statistic(rows) -> None:
    note = rows["Appendix E chi-square (5 x 2)"].note
    assert "Baseline 48/79" in note and "B2 44/80" in note and "B3 64/80" in note
    assert "differ from the printed percentages in Baseline, B2, B3" in note
    assert "needs Baseline 48/79 vs B4 56/80" in rows["Appendix E Fisher p, B4"].note
    assert "with Baseline 48/79 it is 0.607" in rows["Appendix E Fisher p, Neutral"].note


def test_no_statistics_row_fails(rows: dict) -> None:
    assert [r.name for r in rows.values() if r.failed] == []
