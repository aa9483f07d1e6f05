"""thresholds.yaml: schema, and errors naming file, line and allowed values."""

from __future__ import annotations

from pathlib import Path

import pytest

from pytest_emrd.errors import ConfigError
from pytest_emrd.gate import parse_thresholds

METRICS = ("aec", "te", "never_visited")


def _parse(text: str):
    return parse_thresholds(
        text,
        source="thresholds.yaml",
        is_model=lambda n: n in ("scout", "gemini"),
        model_names=("gemini", "scout"),
        metrics=METRICS,
    )


def test_worked_example():
    t = _parse(
        "scout:\n  baseline:\n    aec: {min: 0.8, ci: lower}\n    never_visited: {max: 0.1}\n"
        "gemini:\n  texture:\n    te: {min: 0.2}\n"
    )
    first, second, third = t.bounds
    assert (first.metric, first.kind, first.value, first.ci, first.line) == (
        "aec",
        "min",
        0.8,
        "lower",
        3,
    )
    assert (second.kind, second.value, second.ci) == ("max", 0.1, None)
    assert t.for_cell("gemini", "texture") == (third,)
    assert [b.model for b in t.bounds] == ["scout", "scout", "gemini"]


@pytest.mark.parametrize(
    "text", ["", "# gates come later\n", "scout: {}\n"], ids=["empty", "comments", "no-metric"]
)
def test_a_file_without_gates_is_an_error(text):
    with pytest.raises(ConfigError, match="holds no gate, so a run would pass with nothing"):
        _parse(text)


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("scout: [1, 2", "line 1, column 13: malformed YAML"),
        ("claude3:\n  baseline: {}\n", "line 1: unknown model 'claude3'; allowed: gemini, scout"),
        (
            "scout:\n  fog: {}\n",
            "line 2: unknown condition 'fog'; allowed: baseline, low_light, texture",
        ),
        (
            "scout:\n  baseline:\n    speed: {min: 1}\n",
            "line 3: unknown metric 'speed'; allowed: aec, never_visited, te",
        ),
        (
            "scout:\n  baseline:\n    aec: {min: 1, max: 2}\n",
            "line 3: scout.baseline.aec needs exactly one of min or max",
        ),
        ("scout:\n  baseline:\n    aec: {}\n", "needs exactly one of min or max, got none"),
        (
            "scout:\n  baseline:\n    aec: {min: high}\n",
            "line 3: scout.baseline.aec.min must be a number",
        ),
        (
            "scout:\n  baseline:\n    aec: {min: 1, ci: middle}\n",
            "unknown ci side in scout.baseline.aec 'middle'; allowed: lower, upper",
        ),
        (
            "scout:\n  baseline:\n    aec: {minimum: 1}\n",
            "unknown key in scout.baseline.aec 'minimum'",
        ),
        ("scout:\n  baseline: 3\n", "line 2: scout.baseline must be a mapping"),
        ("scout:\n  baseline: {}\nscout:\n  texture: {}\n", "line 3: 'scout' appears twice"),
    ],
    ids=[
        "malformed",
        "model",
        "condition",
        "metric",
        "both-bounds",
        "no-bound",
        "not-number",
        "ci-side",
        "bound-key",
        "not-mapping",
        "duplicate",
    ],
)
def test_bad_thresholds_name_file_line_and_allowed_values(text, message):
    with pytest.raises(ConfigError) as info:
        _parse(text)
    assert str(info.value).startswith("thresholds.yaml, line ")
    assert message in str(info.value)


def test_the_shipped_thresholds_file_is_valid():
    from pytest_emrd.agent import load_registry
    from pytest_emrd.gate import load_thresholds
    from pytest_emrd.metrics import GATE_METRICS

    root = Path(__file__).resolve().parents[2]
    thresholds = load_thresholds(
        root / "thresholds.yaml", registry=load_registry(), metrics=GATE_METRICS
    )
    assert {"scout", "gemini", "gpt", "claude", "qwen3-vl-32b"} <= {
        b.model for b in thresholds.bounds
    }


def test_missing_thresholds_file_says_how_to_fix(tmp_path):
    from pytest_emrd.agent import load_registry
    from pytest_emrd.gate import load_thresholds

    with pytest.raises(ConfigError, match="--emrd-thresholds"):
        load_thresholds(tmp_path / "nope.yaml", registry=load_registry(), metrics=())


def test_generated_layout_bounds_are_their_own_cells():
    t = _parse(
        "scout:\n  baseline:\n    aec: {min: 0.9}\n  baseline@generated:\n    aec: {min: 0.7}\n"
    )
    paper, generated = t.bounds
    assert (paper.layouts, generated.layouts) == ("paper", "generated")
    assert t.for_cell("scout", "baseline") == (paper,)
    assert t.for_cell("scout", "baseline", "generated") == (generated,)


@pytest.mark.parametrize("key", ["baseline@many", "baseline@paper", "baseline@"])
def test_unknown_layouts_qualifier_names_the_allowed_one(key):
    with pytest.raises(ConfigError, match=r"line 2: unknown layouts after '@'.*allowed: generated"):
        _parse(f"scout:\n  {key}:\n    aec: {{min: 0.9}}\n")
