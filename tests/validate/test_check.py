"""Check rows, the report's JSON round trip, the Markdown table, bad input."""

from __future__ import annotations

import json
import math

import pytest

from pytest_emrd.errors import ConfigError, ProtocolError
from pytest_emrd.validate import (
    FAMILIES,
    GROUPS,
    MIMIC_MODELS,
    Check,
    Plan,
    ValidationReport,
    episode_checks,
    markdown,
    to_json,
)


def _report() -> ValidationReport:
    return ValidationReport(
        (
            Check(
                section="Remember",
                name="EFC | pooled",
                planted="8 steps",
                recovered="inf steps",
                tolerance="within 25 %",
                verdict="fail",
                note="no event",
                data={"efc": math.inf},
            ),
            Check(
                section="Statistics",
                name="chi-square",
                planted="62.4",
                recovered="62.43",
                tolerance="printed precision",
                verdict="pass",
            ),
            Check(
                section="Statistics",
                name="p",
                planted="< 1e-13",
                recovered="1.8e-13",
                tolerance="printed precision",
                verdict="finding",
            ),
        ),
        episodes=2,
        protocol="builtin-1+p1",
    )


def test_json_is_strict_and_round_trips() -> None:
    text = to_json(_report())
    data = json.loads(text)
    assert data["checks"][0]["data"] == {"efc": "inf"}
    back = ValidationReport.from_dict(data)
    assert [c.verdict for c in back.checks] == ["fail", "pass", "finding"]
    assert [c.name for c in back.failed] == ["EFC | pooled"]


def test_markdown_groups_by_section_and_escapes_pipes() -> None:
    text = markdown(_report())
    assert text.startswith("3 checks: 1 pass, 1 fail, 1 finding (2 episodes")
    assert text.index("### Remember") < text.index("### Statistics")
    assert "EFC \\| pooled" in text and "**fail**" in text and "**finding**" in text


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        pytest.param({"verdict": "ok"}, "verdict='ok' is not one of", id="bad-verdict"),
        pytest.param({"section": "Maps"}, "section='Maps' is not one of", id="bad-section"),
    ],
)
def test_bad_check(kwargs: dict, message: str) -> None:
    base = {"section": "Remember", "name": "x", "planted": "1", "recovered": "1",
            "tolerance": "exact", "verdict": "pass"}  # fmt: skip
    with pytest.raises(ConfigError, match=message):
        Check(**{**base, **kwargs})


@pytest.mark.parametrize("episodes", [0, -1, 1.5, True], ids=["zero", "negative", "float", "bool"])
def test_bad_plan(episodes: object) -> None:
    with pytest.raises(ConfigError, match="episodes="):
        Plan(episodes)  # type: ignore[arg-type]


def test_report_from_another_schema_is_refused() -> None:
    data = _report().to_dict() | {"schema_version": 99}
    with pytest.raises(ProtocolError, match="schema_version=99"):
        ValidationReport.from_dict(data)


def test_plan_pairs_groups_over_the_same_offices() -> None:
    plan = Plan(2)
    specs = plan.specs()
    assert len(specs) == 2 * 4 * len(plan.groups)
    seeds = {g.name: [s.seed for s in g.specs(2)] for g in plan.groups}
    assert len({tuple(v) for v in seeds.values()}) == 1
    assert {s.modality for s in specs} == {"both"}


def test_families_partition_the_groups() -> None:
    scout, mimic = set(FAMILIES["scout"]), set(FAMILIES["mimic"])
    assert scout | mimic == set(GROUPS) and not scout & mimic
    assert {g.model for g in mimic} == set(MIMIC_MODELS.values())


def test_rows_come_only_for_the_families_run() -> None:
    assert episode_checks({}) == []
