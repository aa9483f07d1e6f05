"""examples/ci/emrd.yml: what a model team's own repository needs from its workflow.

The workflow's commands are run, in order, in such a repository (installed from a built
wheel) by tests/test_wheel.py; this module checks what a local run cannot see: permissions,
concurrency, time limits, the pip cache, the registry on every command that reads
thresholds.yaml, and the action versions.
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import pytest
import yaml

ROOT = Path(__file__).resolve().parents[1]
WORKFLOW = ROOT / "examples" / "ci" / "emrd.yml"
#: The current major version of each action the workflow uses (their release pages).
MAJORS = {
    "actions/checkout": 6,
    "actions/setup-python": 6,
    "actions/upload-artifact": 7,
    "actions/download-artifact": 8,
}


@pytest.fixture(scope="module")
def workflow() -> dict[str, Any]:
    return yaml.safe_load(WORKFLOW.read_text(encoding="utf-8"))


def _runs(job: dict[str, Any]) -> list[str]:
    return [step["run"] for step in job["steps"] if "run" in step]


def test_least_privilege_one_run_per_ref_and_time_limits(workflow) -> None:
    assert workflow["permissions"] == {"contents": "read"}
    assert "github.ref" in workflow["concurrency"]["group"]
    assert workflow["concurrency"]["cancel-in-progress"] is True
    for name, job in workflow["jobs"].items():
        assert 0 < job["timeout-minutes"] <= 60, name


def test_pip_is_cached_on_the_pinned_package(workflow) -> None:
    for name, job in workflow["jobs"].items():
        setup = next(s for s in job["steps"] if s.get("uses", "").startswith("actions/setup-"))
        assert setup["with"]["cache"] == "pip", name
        # the team's repository has no requirements file: the workflow's pin is the key
        assert setup["with"]["cache-dependency-path"] == ".github/workflows/emrd.yml", name
        assert _runs(job)[0] == 'python -m pip install "${{ env.EMRD_PACKAGE }}"', name
    assert workflow["env"]["EMRD_PACKAGE"].startswith("pytest-emrd==")


def test_the_suite_comes_from_the_package_and_the_registry_goes_everywhere(workflow) -> None:
    shard, gate = workflow["jobs"]["shard"], workflow["jobs"]["gate"]
    (replay,) = [r for r in _runs(shard) if "pytest" in r]
    assert replay.startswith("python -m pytest --pyargs pytest_emrd.benchmarks -n 2")
    assert "--emrd-models=${{ env.EMRD_MODELS }}" in replay
    assert "pip install -e" not in WORKFLOW.read_text(encoding="utf-8")
    assert _runs(gate)[-1] == (
        "emrd gate runs/* --thresholds thresholds.yaml --models ${{ env.EMRD_MODELS }}"
    )
    assert workflow["env"]["EMRD_MODELS"] == "models.yaml"


def test_shards_then_gate(workflow) -> None:
    shard, gate = workflow["jobs"]["shard"], workflow["jobs"]["gate"]
    matrix = shard["strategy"]["matrix"]
    assert matrix["shard"] == list(range(1, int(workflow["env"]["EMRD_SHARDS"]) + 1))
    assert shard["strategy"]["fail-fast"] is False
    assert gate["needs"] == "shard" and "!cancelled()" in gate["if"]
    assert any(s.get("uses", "").startswith("actions/upload-artifact@") for s in shard["steps"])


def test_current_major_versions_of_the_actions(workflow) -> None:
    used = [s["uses"] for job in workflow["jobs"].values() for s in job["steps"] if "uses" in s]
    assert {u.partition("@")[0] for u in used} == set(MAJORS)
    for use in used:
        action, _, version = use.partition("@")
        assert re.fullmatch(r"v\d+", version), use
        assert int(version[1:]) == MAJORS[action], use
