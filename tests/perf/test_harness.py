"""``python -m perf``: warm figures in this process, cold ones in a fresh copy and process."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from perf import COLD_ENV, ROOT, cold_env, fresh_copy, python_env
from perf.__main__ import main


def _checkout(root: Path) -> Path:
    for package in ("pytest_emrd", "perf", "benchmarks"):
        (root / package / "__pycache__").mkdir(parents=True)
        (root / package / "__init__.py").write_text("")
        (root / package / "__pycache__" / "__init__.cpython-311.pyc").write_bytes(b"old")
    (root / "pyproject.toml").write_text("[project]\n")
    (root / "thresholds.yaml").write_text("{}\n")
    (root / "cassettes").mkdir()
    return root


def test_a_fresh_copy_holds_the_sources_and_no_cache(tmp_path: Path) -> None:
    root = _checkout(tmp_path / "root")
    (tmp_path / "into").mkdir()
    copy = fresh_copy(root, tmp_path / "into")
    assert (copy / "pytest_emrd" / "__init__.py").exists()
    assert (copy / "pyproject.toml").read_text() == "[project]\n"
    assert not list(copy.rglob("__pycache__")) and not list(copy.rglob("*.pyc"))
    assert (copy / "cassettes").is_symlink()
    assert (copy / "cassettes").resolve() == (root / "cassettes").resolve()


def test_a_cold_environment_imports_the_copy_with_empty_caches(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv("PYTHONPYCACHEPREFIX", "/somewhere/warm")
    monkeypatch.setenv("PYTHONDONTWRITEBYTECODE", "1")
    monkeypatch.setenv("PYTHONPATH", "/elsewhere")
    env = cold_env(tmp_path)
    assert env["PYTHONPATH"].split(":") == [str(tmp_path), "/elsewhere"]
    assert "PYTHONPYCACHEPREFIX" not in env and "PYTHONDONTWRITEBYTECODE" not in env
    assert env[COLD_ENV] == "1"


def test_timed_commands_cache_bytecode_apart_when_warm_and_beside_the_copy_when_cold(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.delenv(COLD_ENV, raising=False)
    assert "PYTHONPYCACHEPREFIX" in python_env(bytecode=True)
    assert python_env(bytecode=False)["PYTHONDONTWRITEBYTECODE"] == "1"
    monkeypatch.setenv(COLD_ENV, "1")
    assert "PYTHONPYCACHEPREFIX" not in python_env(bytecode=True)
    assert "PYTHONDONTWRITEBYTECODE" not in python_env(bytecode=True)


def test_an_unknown_stage_is_one_line_naming_the_stages(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["worlds"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("python -m perf: error: stage='worlds' is not one of 'world', ")
    assert "'all'" in err


def test_a_cold_stage_refuses_to_measure_another_checkout(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    import perf.__main__

    monkeypatch.setenv(COLD_ENV, "1")
    monkeypatch.setattr(perf.__main__, "ROOT", tmp_path)
    assert main(["world"]) == 2
    err = capsys.readouterr().err
    assert "not from the fresh copy" in err and str(tmp_path) in err


@pytest.mark.slow
def test_one_command_prints_warm_and_cold_figures_as_json() -> None:
    done = subprocess.run(
        [sys.executable, "-m", "perf", "world", "--repeat", "1", "--json"],
        cwd=ROOT,
        capture_output=True,
        text=True,
        check=True,
    )
    figures = {f["figure"]: f for f in json.loads(done.stdout)}
    warm = [name for name in figures if not name.endswith("_cold")]
    assert "world.episode_s" in warm
    assert set(figures) == {*warm, *(f"{name}_cold" for name in warm)}
    for name in warm:
        cold = figures[f"{name}_cold"]
        assert {"figure", "value", "unit", "target", "n"} <= set(cold)
        assert (cold["unit"], cold["target"], cold["n"]) == (
            figures[name]["unit"],
            figures[name]["target"],
            1,
        )
        assert cold["value"] > 0 and figures[name]["value"] > 0
