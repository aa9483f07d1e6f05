"""Probes 2, 3, 6 and 7: every bad input is one line naming the file, the line, the field and
the allowed values; ``emrd gate`` and pytest print the same text."""

from __future__ import annotations

import math
from pathlib import Path

import pytest
from hypothesis import given
from hypothesis import strategies as st

from pytest_emrd.agent import load_registry
from pytest_emrd.cli import main as emrd
from pytest_emrd.errors import ConfigError
from pytest_emrd.gate import load_thresholds
from pytest_emrd.gate._thresholds import domain
from pytest_emrd.metrics import GATE_METRICS
from pytest_emrd.run import RECORD_MODES, resolve_settings
from pytest_emrd.run._settings import in_ci
from tests._sandbox import Sandbox

ROOT = Path(__file__).resolve().parents[2]
FLAG = "--emrd-thresholds (emrd gate --thresholds)"


def _gates(tmp_path: Path, content: bytes | None) -> Path:
    path = tmp_path / "thresholds.yaml"
    if content is None:
        path.mkdir()
    else:
        path.write_bytes(content)
    return path


THRESHOLD_PROBES = [
    (
        b"scout:\n  baseline:\n    aec: {min: 0.5}\n\xff\xfe",
        "thresholds file {path}, line 4: byte 0xff at offset 39 is not UTF-8; save the file as "
        "UTF-8 text (a YAML file, not a binary), or pass another one with " + FLAG + ".",
    ),
    (
        None,
        "thresholds file {path} is a directory, not a file; pass the YAML file itself with "
        + FLAG
        + ".",
    ),
    (
        b"scout:\n  baseline:\n    aec: {min: 1.5}\n",
        "{path}, line 3: scout.baseline.aec.min=1.5 is outside the metric's domain; write a "
        "fraction in [0, 1].",
    ),
    (
        b"scout:\n  baseline:\n    never_visited: {max: -0.2}\n",
        "{path}, line 3: scout.baseline.never_visited.max=-0.2 is outside the metric's domain; "
        "write a fraction in [0, 1].",
    ),
    (
        b"scout:\n  baseline:\n    pa: {min: .nan}\n",
        "{path}, line 3: scout.baseline.pa.min=.nan is outside the metric's domain; write a "
        "fraction in [0, 1].",
    ),
    (
        b"scout:\n  baseline:\n    te: {max: 1e9}\n",
        "{path}, line 3: scout.baseline.te.max=1e9 is outside the metric's domain; write steps "
        "in [0, 50] (the action budget).",
    ),
    (
        b"scout:\n  baseline:\n    ebbinghaus_r2: {min: 1.2}\n",
        "{path}, line 3: scout.baseline.ebbinghaus_r2.min=1.2 is outside the metric's domain; "
        "write an R^2 <= 1.",
    ),
    (
        b"scout:\n  baseline:\n    aec: {min: [0.5]}\n",
        "{path}, line 3: scout.baseline.aec.min must be a number (a fraction in [0, 1]), got a "
        "list.",
    ),
    (
        b"scout:\n  baseline: 0.5\n",
        "{path}, line 2: scout.baseline must be a mapping of name: value, got '0.5'.",
    ),
    (
        b"scout:\n  baseline:\n    aec: {min: 0.5\n",
        "{path}, line 4, column 1: malformed YAML (while parsing a flow mapping: expected ',' or "
        "'}', but got '<stream end>').",
    ),
    (
        b"mine:\n  baseline:\n    aec: {min: 0.5}\n",
        "{path}, line 1: unknown model 'mine'; allowed: {models}. A model of your own "
        "registry must be registered for every run that reads this file: set `emrd_models = "
        "FILE` in the pytest ini (or pass --emrd-models FILE), and --models FILE to `emrd gate` "
        "and `emrd report`.",
    ),
]
IDS = [
    "not-utf8",
    "directory",
    "fraction-above-1",
    "fraction-below-0",
    "nan",
    "te-beyond-budget",
    "r2-above-1",
    "list-not-number",
    "condition-not-mapping",
    "malformed",
    "unknown-user-model",
]


@pytest.mark.parametrize(("content", "message"), THRESHOLD_PROBES, ids=IDS)
def test_a_bad_thresholds_file_is_one_line_in_the_library_and_in_emrd_gate(
    tmp_path, capsys, content, message
):
    path = _gates(tmp_path, content)
    models = ", ".join(load_registry().names())
    expected = message.replace("{path}", str(path)).replace("{models}", models)
    with pytest.raises(ConfigError) as info:
        load_thresholds(path, registry=load_registry(), metrics=GATE_METRICS)
    assert str(info.value) == expected
    assert "ScalarNode" not in expected and "\n" not in expected
    run = tmp_path / "run"
    (run / "episodes").mkdir(parents=True)
    assert emrd(["gate", str(run), "--thresholds", str(path)]) == 2
    assert capsys.readouterr().err == f"emrd gate: error: {expected}\n"


def test_yaml_1_2_floats_are_numbers(tmp_path):
    path = _gates(tmp_path, b"scout:\n  baseline:\n    memory_strength: {min: 1e1}\n")
    (bound,) = load_thresholds(path, registry=load_registry(), metrics=GATE_METRICS).bounds
    assert bound.value == 10.0


@given(st.floats(allow_nan=True, allow_infinity=True))
def test_a_fraction_bound_loads_iff_it_is_a_finite_fraction(value):
    text = f"scout:\n  baseline:\n    aec: {{min: {value!r}}}\n".replace("nan", ".nan")
    text = text.replace("inf", ".inf")
    from pytest_emrd.gate import parse_thresholds

    ok = math.isfinite(value) and 0.0 <= value <= 1.0
    try:
        parse_thresholds(
            text, source="t.yaml", is_model=lambda m: True, model_names=(), metrics=GATE_METRICS
        )
    except ConfigError as exc:
        assert not ok and str(exc).startswith("t.yaml, line 3: scout.baseline.aec.min=")
    else:
        assert ok


def test_every_gate_metric_has_a_domain():
    for name, metric in GATE_METRICS.items():
        assert domain(name, metric.unit).text != "a finite number", name


REGISTRY_FLAG = "--emrd-models (emrd gate --models)"


@pytest.mark.parametrize(
    ("content", "message"),
    [
        (
            b"models:\n  m: {provider: openai}\n\x89PNG",
            "model registry file {path}, line 3: byte 0x89 at offset 32 is not UTF-8; save the "
            "file as UTF-8 text (a YAML file, not a binary), or pass another one with "
            + REGISTRY_FLAG
            + ".",
        ),
        (
            None,
            "model registry file {path} is a directory, not a file; pass the YAML file "
            "itself with " + REGISTRY_FLAG + ".",
        ),
        (
            b"models:\n  m: [\n",
            "{path}, line 3, column 1: malformed YAML (while parsing a flow node: expected the "
            "node content, but found '<stream end>').",
        ),
        (
            b"models:\n  m: {provider: openai, model_id: x, base_url: 'http://h', "
            b"timeout_s: 1e9}\n",
            "{path}, line 2: model 'm': timeout_s=1000000000.0 must lie in [0.001, 3600.0].",
        ),
    ],
    ids=["not-utf8", "directory", "malformed", "yaml12-float-out-of-range"],
)
def test_a_bad_registry_file_is_one_line(tmp_path, capsys, content, message):
    path = tmp_path / "models.yaml"
    if content is None:
        path.mkdir()
    else:
        path.write_bytes(content)
    expected = message.replace("{path}", str(path))
    with pytest.raises(ConfigError) as info:
        load_registry(path)
    assert str(info.value) == expected
    run = tmp_path / "run"
    (run / "episodes").mkdir(parents=True)
    assert emrd(["gate", str(run), "--models", str(path)]) == 2
    assert capsys.readouterr().err == f"emrd gate: error: {expected}\n"


@pytest.mark.parametrize(
    ("value", "ci"),
    [("", False), ("0", False), ("false", False), ("False", False), ("no", False),
     ("off", False), ("1", True), ("true", True), ("yes", True), ("github", True)],
)  # fmt: skip
def test_ci_counts_only_when_it_means_yes(tmp_path, value, ci):
    assert in_ci({"CI": value}) is ci
    settings = resolve_settings({}, {}, rootdir=tmp_path, env={"CI": value})
    assert settings.record_mode == ("none" if ci else "once")
    assert settings.record_mode in RECORD_MODES


def test_episodes_are_capped_with_a_clear_message(tmp_path):
    with pytest.raises(ConfigError) as info:
        resolve_settings({"episodes": "99999999999999999999"}, {}, rootdir=tmp_path, env={})
    assert str(info.value) == (
        "--emrd-episodes=99999999999999999999 is more than 1000 episodes per spawn room (the "
        "paper runs 20); pass at most 1000, or split a larger study over several run "
        "directories."
    )


@pytest.fixture
def suite(sandbox: Sandbox) -> Sandbox:
    sandbox.makepyfile(test_emrd=(ROOT / "benchmarks" / "test_emrd.py").read_text())
    return sandbox


@pytest.mark.slow
@pytest.mark.parametrize(
    ("args", "setup", "message"),
    [
        (
            ["--emrd-results=taken.txt"],
            "taken.txt",
            "ERROR: --emrd-results={root}/taken.txt is a file; pass a directory (a new one, or a "
            "run directory to resume).",
        ),
        (
            ["--emrd-thresholds=gates.yaml"],
            "gates.yaml",
            "pytest-emrd: thresholds file {root}/gates.yaml, line 1: byte 0xff at offset 0 is not "
            "UTF-8; save the file as UTF-8 text (a YAML file, not a binary), or pass another one "
            "with " + FLAG + ".",
        ),
        (
            ["--emrd-model=nope"],
            None,
            "pytest-emrd: model='nope' is not in the registry.*",
        ),
    ],
    ids=["results-is-a-file", "binary-thresholds", "unknown-model"],
)
def test_pytest_prints_one_line_once(suite, args, setup, message):
    if setup:
        (suite.path / setup).write_bytes(b"\xff\xfe\x00")
    result = suite.runpytest("-p", "no:cacheprovider", *args)
    assert result.ret != 0
    output = result.stdout.str() + result.stderr.str()
    expected = message.replace("{root}", str(suite.path))
    matching = [line for line in output.splitlines() if _fnmatch(line, expected)]
    assert len(matching) == 1, output
    assert "Traceback" not in output and "During handling" not in output


def _fnmatch(line: str, pattern: str) -> bool:
    from fnmatch import fnmatchcase

    return fnmatchcase(line, pattern.replace("[", "[[]"))
