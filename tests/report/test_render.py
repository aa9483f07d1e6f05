"""Rendered files: every table and figure present, self-contained well-formed HTML, strict JSON."""

from __future__ import annotations

import io
import json
import math
from html.parser import HTMLParser

import pytest
from PIL import Image

from pytest_emrd.errors import ConfigError
from pytest_emrd.report import FIGURES, Report, build_report, render_files, step_summary_markdown
from pytest_emrd.trajectory import Trajectory

_VOID = {"meta", "img", "br", "hr", "link", "input"}
TABLE_IDS = ("usage", "exploration", "pa", "focal-syn", "fpsg", "ebbinghaus", "anova",
             "serial-position", "intervention-syn-baseline", "inventory-syn-baseline",
             "reasoning")  # fmt: skip


class _Checker(HTMLParser):
    """Tracks the open-tag stack (well-formedness), img sources and table ids."""

    def __init__(self) -> None:
        super().__init__()
        self.stack: list[str] = []
        self.errors: list[str] = []
        self.images: list[str] = []
        self.tables: list[str] = []

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        a = dict(attrs)
        if tag == "img":
            self.images.append(a.get("src") or "")
        if tag == "table":
            self.tables.append(a.get("id") or "")
        if tag not in _VOID:
            self.stack.append(tag)

    def handle_endtag(self, tag: str) -> None:
        if not self.stack or self.stack[-1] != tag:
            self.errors.append(f"</{tag}> closes {self.stack[-1:] or 'nothing'}")
        else:
            self.stack.pop()


@pytest.fixture(scope="module")
def report(variant_grid: list[Trajectory], embed) -> Report:
    return build_report(variant_grid, embed=embed)


@pytest.fixture(scope="module")
def files(report: Report) -> dict[str, bytes]:
    return render_files(report)


def test_every_file_and_figure_is_rendered(files: dict[str, bytes]) -> None:
    assert set(files) == {"report.md", "report.html", "report.json", *(f.name for f in FIGURES)}
    for f in FIGURES:
        image = Image.open(io.BytesIO(files[f.name]))
        assert image.format == "PNG" and image.width >= 600 and image.height >= 300


def test_html_is_well_formed_and_self_contained(files: dict[str, bytes]) -> None:
    checker = _Checker()
    checker.feed(files["report.html"].decode())
    checker.close()
    assert checker.errors == [] and checker.stack == []
    assert len(checker.images) == len(FIGURES)
    assert all(src.startswith("data:image/png;base64,") for src in checker.images)
    assert set(TABLE_IDS) <= set(checker.tables)
    page = files["report.html"].decode()
    assert 'src="http' not in page and "<link" not in page and "<script" not in page


def test_focal_cells_are_shaded_like_the_paper(files: dict[str, bytes]) -> None:
    page = files["report.html"].decode()
    assert 'style="background: rgba(31, 95, 191, 1.00); color: #fff">100.0</td>' in page


def test_markdown_has_every_section_and_figure(files: dict[str, bytes]) -> None:
    md = files["report.md"].decode()
    for title in ("## Gates", "## Exploration Competence", "## Focal-Point distribution",
                  "## Focal-Point Spatial Grounding", "## Ebbinghaus memory strength",
                  "## Serial Position Effect", "## Controlled interventions",
                  "## Representative reasoning", "## Figures"):  # fmt: skip
        assert title in md
    for f in FIGURES:
        assert f"![{f.title}]({f.name})" in md


def test_markdown_numbers_are_the_report_numbers(report: Report, files) -> None:
    md = files["report.md"].decode()
    row = report.exploration[0]
    aec = f"{100 * row.aec.value:.1f} ± {100 * row.aec_sd:.1f} (n={row.aec.n})"
    assert f"| syn | {aec} |" in md
    fpsg = report.fpsg[0].summary
    assert f"{fpsg.local_mean:.3f} ± {fpsg.local_sd:.3f}" in md


def test_json_is_strict_and_holds_every_aggregate(report: Report, files) -> None:
    def reject(constant: str) -> None:
        raise ValueError(f"non-standard JSON constant {constant}")

    data = json.loads(files["report.json"], parse_constant=reject)
    assert data["schema_version"] == 1
    assert data["exploration"][0]["aec"]["value"] == report.exploration[0].aec.value
    assert len(data["km"]) == len(report.km)
    assert data["tbs"][0]["curve"]["mean"] == list(report.tbs[0].curve.mean)


def test_unbounded_memory_strength_is_a_string_in_json(grid: list[Trajectory]) -> None:
    import dataclasses

    # never forget: every step's map is the union of everything mapped so far
    t = grid[0]
    steps, union = [], {}
    for s in t.steps:
        union.update({e.label: e for e in s.cognitive_map})
        steps.append(dataclasses.replace(s, cognitive_map=tuple(union.values())))
    perfect = dataclasses.replace(t, steps=tuple(steps))
    report = build_report([perfect], with_reasoning=False)
    efc = report.ebbinghaus[0].fit.pooled.efc
    assert efc is not None and math.isinf(efc)
    data = json.loads(render_files(report, ["json"])["report.json"])
    assert data["ebbinghaus"][0]["fit"]["pooled"]["efc"] == "inf"


@pytest.mark.parametrize(
    ("formats", "expected"),
    [(["json"], {"report.json"}), (["html"], {"report.html"}), (["md", "md"], None)],
    ids=["json-only", "html-only-no-pngs", "duplicates-collapse"],
)
def test_formats_select_files(report: Report, formats, expected) -> None:
    files = render_files(report, formats)
    if expected is None:
        assert "report.md" in files and "report.html" not in files
    else:
        assert set(files) == expected


@pytest.mark.parametrize("bad", ["pdf", "", "MD"], ids=["pdf", "empty", "upper-case"])
def test_unknown_format_is_a_config_error(report: Report, bad: str) -> None:
    with pytest.raises(ConfigError, match=rf"format='{bad}' is not one of 'md', 'html', 'json'"):
        render_files(report, [bad])


def test_step_summary_markdown(grid: list[Trajectory]) -> None:
    from pytest_emrd.gate import Bound, GateCell, evaluate_cell
    from pytest_emrd.metrics import GATE_METRICS

    cell = [t for t in grid if t.spec.condition == "baseline"]
    verdict = evaluate_cell(GateCell(Bound("syn", "baseline", "aec", "min", 0.99)), cell,
                            GATE_METRICS)  # fmt: skip
    md = step_summary_markdown(grid, [verdict])
    assert md.startswith("# EMRD results\n")
    assert "0/1 gates pass (thresholds)." in md
    assert "| syn | Baseline | default | aec |" in md and "**FAIL**" in md
    assert "## Exploration Competence" in md and "## Focal-Point Spatial Grounding" in md
    assert "![" not in md and "Representative reasoning" not in md
    assert "No thresholds file" in step_summary_markdown(grid, [])


def test_the_pa_table_holds_the_figures_numbers(report: Report, files) -> None:
    import numpy as np

    md = files["report.md"].decode()
    assert "## Positional Accuracy" in md
    g = next(g for g in report.pa if len(g.values) > 1)
    row = f"{np.mean(g.values):.3f} ± {np.std(g.values, ddof=1):.3f} (n={len(g.values)})"
    assert row in md


def test_conditions_carry_their_gate_keys_and_units_are_stated(grid) -> None:
    """The gate row names the condition as thresholds.yaml does, in the file's unit."""
    from pytest_emrd.gate import Bound, GateCell, evaluate_cell
    from pytest_emrd.metrics import GATE_METRICS

    cell = [t for t in grid if t.spec.condition == "low_light"]
    verdict = evaluate_cell(GateCell(Bound("syn", "low_light", "aec", "min", 0.5)), cell,
                            GATE_METRICS)  # fmt: skip
    md = render_files(build_report(grid, verdicts=[verdict], with_reasoning=False),
                      ["md"])["report.md"].decode()  # fmt: skip
    assert f"| syn | Light & Vis. (low_light) | default | aec | {verdict.value:.3f} |" in md
    assert "rates and shares as fractions (0.9), which the tables below print as " in md
    assert "AEC (%) Light & Vis. (low_light)" in md and "Texture & Col. (texture)" in md


def test_a_negative_r2_gets_a_caveat(report: Report) -> None:
    import dataclasses

    from pytest_emrd.report._sections import ebbinghaus

    row = report.ebbinghaus[0]
    fit = dataclasses.replace(row.fit, pooled=dataclasses.replace(row.fit.pooled, r2=-1304.58))
    bad = dataclasses.replace(report, ebbinghaus=(dataclasses.replace(row, fit=fit),
                                                  *report.ebbinghaus[1:]))  # fmt: skip
    text = str(ebbinghaus(bad))
    assert "R² below 0 means the exponential fits the KM curve worse" in text
    assert "(R² -1304.58)" in text
    assert "R² below 0" not in str(ebbinghaus(report)) or any(
        r.fit.pooled.r2 is not None and r.fit.pooled.r2 < 0 for r in report.ebbinghaus
    )


def test_an_unpriced_model_says_why_its_cost_is_na(grid) -> None:
    md = render_files(build_report(grid, with_reasoning=False), ["md"])["report.md"].decode()
    assert "Est. cost n/a for syn: the registry this report read has no price" in md
    assert "pass `--models FILE` to `emrd report`" in md
    priced = build_report(grid, with_reasoning=False, prices={"syn": (1.0, 2.0)})
    assert "Est. cost n/a" not in render_files(priced, ["md"])["report.md"].decode()
