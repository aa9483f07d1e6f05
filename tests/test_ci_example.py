"""examples/ci/emrd.yml: what a model team's own repository needs from its workflow.

The workflow runs, job by job, in a temporary team repository with a grid smaller than the
paper's (2 recorded episodes per spawn room, a registry with prices, no network on replay):
the team's day from the first red build to the fix. tests/test_wheel.py runs it again from a
built wheel; the rest of this module checks what a local run cannot see: permissions,
concurrency, time limits, the pip cache, the registry on every command that reads
thresholds.yaml, and the action versions.
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest
import yaml

from pytest_emrd.agent import REFERENCE_VERSION
from tests._workflow import LocalRunner

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


MODEL = "my-vlm"
#: The team's registry: the built-in scout's requests under the team's name, priced, served
#: at an address nothing answers (a replay that went to the network would fail).
MODELS_YAML = f"""\
models:
  {MODEL}:
    provider: openai
    base_url: "http://127.0.0.1:9/v1"
    model_id: scout@{REFERENCE_VERSION}
    api_key_env: MY_VLM_API_KEY
    api_key_required: false
    modality: both
    price_per_mtok_in: 1.0
    price_per_mtok_out: 4.0
"""


@pytest.fixture(scope="module")
def team(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, dict[str, str]]:
    """The team's repository (2 recorded episodes per spawn room, the workflow with
    ``EMRD_EPISODES`` edited to match) and the shell its jobs run in."""
    repo = tmp_path_factory.mktemp("team") / "repo"
    for path in (ROOT / "cassettes" / "scout").glob("*/default/*/ep0[01].json.xz"):
        target = repo / "cassettes" / MODEL / path.relative_to(ROOT / "cassettes" / "scout")
        target.parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(path, target)
    (repo / "models.yaml").write_text(MODELS_YAML, encoding="utf-8")
    text = WORKFLOW.read_text(encoding="utf-8")
    assert 'EMRD_EPISODES: "20"' in text
    workflows = repo / ".github" / "workflows"
    workflows.mkdir(parents=True)
    (workflows / "emrd.yml").write_text(text.replace('EMRD_EPISODES: "20"', 'EMRD_EPISODES: "2"'))
    env = {k: v for k, v in os.environ.items() if k not in {"PYTHONPATH", "GITHUB_STEP_SUMMARY"}}
    env.update(CI="true", PATH=f"{Path(sys.executable).parent}{os.pathsep}{env['PATH']}")
    return repo, env


def _jobs(repo: Path) -> tuple[dict[str, Any], dict[str, str]]:
    workflow = yaml.safe_load((repo / ".github/workflows/emrd.yml").read_text(encoding="utf-8"))
    # this checkout is installed already (editable): the install step finds it satisfied
    return workflow, {**workflow["env"], "EMRD_PACKAGE": "pytest-emrd"}


def _shards(runner: LocalRunner, workflow: dict[str, Any], values: dict[str, str]) -> None:
    for shard in workflow["jobs"]["shard"]["strategy"]["matrix"]["shard"]:
        context = {"matrix": {"model": MODEL, "shard": shard}, "env": values}
        rc = runner.job(workflow["jobs"]["shard"], context)
        assert rc == 0, runner.last.stdout[-3000:] + runner.last.stderr[-2000:]


@pytest.mark.slow
def test_the_day_after_the_first_red_build(team, tmp_path: Path) -> None:
    repo, env = team
    summary = tmp_path / "step_summary.md"
    runner = LocalRunner(repo, tmp_path / "artifacts", {**env, "GITHUB_STEP_SUMMARY": str(summary)})
    workflow, values = _jobs(repo)
    _shards(runner, workflow, values)
    shard_summary = summary.read_text(encoding="utf-8")
    assert "$" in shard_summary and "Est. cost n/a" not in shard_summary, shard_summary
    assert "no gate ran" in shard_summary and "emrd thresholds" in shard_summary
    assert "no gate ran: no thresholds file" in runner.last.stdout

    runs = sorted(runner.store.iterdir())
    starter = subprocess.run(
        ["emrd", "thresholds", *map(str, runs), "--out", str(repo / "thresholds.yaml")],
        env=env,
        capture_output=True,
        text=True,
        check=False,
    )
    assert starter.returncode == 0, starter.stderr
    assert f"{MODEL}:\n  baseline:\n    aec: {{min: " in (repo / "thresholds.yaml").read_text()
    summary.write_text("", encoding="utf-8")
    assert runner.job(workflow["jobs"]["gate"], {"env": values}) == 0, runner.last.stdout
    assert "FAIL" not in runner.last.stdout and "$" in runner.last.stdout
    assert "$" in summary.read_text(encoding="utf-8")

    (runner.repo / "thresholds.yaml").write_text(
        f"{MODEL}:\n  baseline:\n    aec: {{min: 0.99}}\n", encoding="utf-8"
    )
    assert runner.job(workflow["jobs"]["gate"], {"env": values}) == 1, runner.last.stdout
    out = runner.last.stdout
    assert f"FAIL {MODEL}-baseline-aec" in out and "open them: `emrd view runs/emrd-run-" in out
    assert "open them: `emrd view runs/emrd-run-" in summary.read_text(encoding="utf-8")

    summary.write_text("", encoding="utf-8")
    shutil.rmtree(runs[0])  # its artifact is uploaded again
    context = {"matrix": {"model": MODEL, "shard": 1}, "env": values}
    assert runner.job(workflow["jobs"]["shard"], context) == 0
    assert "gates of thresholds.yaml run over all shards in `emrd gate`" in summary.read_text()

    context["env"] = {**values, "EMRD_EPISODES": "20"}  # the workflow as shipped
    assert runner.job(workflow["jobs"]["shard"], context) != 0
    said = runner.last.stdout + runner.last.stderr
    assert "the cassettes hold 2" in said and "EMRD_EPISODES" in said, said[-3000:]

    compare = subprocess.run(
        ["emrd", "report", "--compare", str(runs[0]), str(runs[0]), "--out", str(tmp_path / "c")],
        env=env,
        capture_output=True,
        text=True,
        check=False,
    )
    assert compare.returncode == 0, compare.stderr
    assert f"{MODEL} baseline aec: " in compare.stdout and ": no change" in compare.stdout
