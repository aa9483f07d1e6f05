"""examples/ci/emrd.yml, run locally: every shard job of the matrix, then the gate job.

The workflow is parsed, its matrix expanded and each step executed in order as GitHub
Actions would: ``run:`` commands through bash with ``${{ matrix.* }}`` and ``${{ env.* }}``
substituted, ``upload-artifact``/``download-artifact`` as copies between folders, checkout
and set-up as no-ops (this checkout and virtualenv), ``pip install`` skipped (the package
under test is already importable). ``EMRD_EPISODES`` is lowered to keep the replay of the
committed scout cassettes short; the checkout's thresholds.yaml holds gates that are meant
to hold on 12 episodes (the shipped bounds are set for the full 240).
"""

from __future__ import annotations

import itertools
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest
import yaml

ROOT = Path(__file__).resolve().parents[1]
WORKFLOW = ROOT / "examples" / "ci" / "emrd.yml"
EXPRESSION = re.compile(r"\$\{\{\s*(?P<expr>[^}]*?)\s*\}\}")

pytestmark = pytest.mark.slow

GATES = """\
scout:
  baseline:
    errored_rate: {max: 0.0}
    aec: {min: 0.9}
    never_visited: {max: 0.0}
  low_light:
    errored_rate: {max: 0.0}
"""


def _substitute(text: str, context: dict[str, dict[str, str]]) -> str:
    def value(match: re.Match[str]) -> str:
        scope, _, name = match["expr"].partition(".")
        if scope not in context or name not in context[scope]:
            raise AssertionError(f"the local runner does not know ${{{{ {match['expr']} }}}}")
        return str(context[scope][name])

    return EXPRESSION.sub(value, text)


class LocalRunner:
    """Runs each job in a fresh copy of ``repo`` (a new runner machine), with artifacts kept
    in ``store`` between jobs."""

    def __init__(self, repo: Path, store: Path, env: dict[str, str]) -> None:
        self.repo, self.store, self.env = repo, store, env
        self.commands: list[str] = []
        self.jobs = 0

    def job(self, job: dict[str, Any], context: dict[str, dict[str, str]]) -> int:
        self.jobs += 1
        self.checkout = self.store.parent / f"job-{self.jobs}"
        shutil.copytree(self.repo, self.checkout, symlinks=True)
        for step in job["steps"]:
            rc = self.step(step, context)
            if rc != 0:
                return rc
        return 0

    def step(self, step: dict[str, Any], context: dict[str, dict[str, str]]) -> int:
        with_ = {k: _substitute(str(v), context) for k, v in (step.get("with") or {}).items()}
        uses = step.get("uses", "")
        if uses.startswith(("actions/checkout@", "actions/setup-python@")):
            return 0
        if uses.startswith("actions/upload-artifact@"):
            shutil.copytree(self.checkout / with_["path"], self.store / with_["name"])
            return 0
        if uses.startswith("actions/download-artifact@"):
            for artifact in sorted(self.store.glob(with_["pattern"])):
                shutil.copytree(artifact, self.checkout / with_["path"] / artifact.name)
            return 0
        assert "run" in step, f"the local runner cannot run step {step}"
        command = _substitute(step["run"], context)
        if command.startswith("pip install"):
            return 0
        self.commands.append(command)
        done = subprocess.run(
            ["bash", "-c", command], cwd=self.checkout, env=self.env, capture_output=True,
            text=True, check=False,
        )  # fmt: skip
        self.last = done
        return done.returncode


@pytest.fixture(scope="module")
def workflow() -> dict[str, Any]:
    return yaml.safe_load(WORKFLOW.read_text(encoding="utf-8"))


@pytest.fixture
def checkout(tmp_path: Path) -> Path:
    """A checkout of this repository: the suite, the committed cassettes and the gates."""
    repo = tmp_path / "repo"
    repo.mkdir()
    (repo / "benchmarks").symlink_to(ROOT / "benchmarks")
    (repo / "cassettes").symlink_to(ROOT / "cassettes")
    (repo / "thresholds.yaml").write_text(GATES, encoding="utf-8")
    return repo


def _env(summary: Path) -> dict[str, str]:
    env = dict(os.environ, CI="true", GITHUB_STEP_SUMMARY=str(summary))
    env["PYTHONPATH"] = os.pathsep.join(filter(None, [str(ROOT), env.get("PYTHONPATH")]))
    env["PATH"] = os.pathsep.join([str(Path(sys.executable).parent), env["PATH"]])
    return env


def test_the_workflow_shape(workflow):
    shard, gate = workflow["jobs"]["shard"], workflow["jobs"]["gate"]
    matrix = shard["strategy"]["matrix"]
    assert matrix["shard"] == list(range(1, int(workflow["env"]["EMRD_SHARDS"]) + 1))
    assert gate["needs"] == "shard" and "!cancelled()" in gate["if"]
    assert any(s.get("uses", "").startswith("actions/upload-artifact@") for s in shard["steps"])
    assert gate["steps"][-1]["run"].startswith("emrd gate runs/*")


def test_shards_then_gate_replay_and_gate_like_one_machine(workflow, checkout, tmp_path):
    summary = tmp_path / "step_summary.md"
    runner = LocalRunner(checkout, tmp_path / "artifacts", _env(summary))
    env = {**workflow["env"], "EMRD_EPISODES": "1"}
    matrix = workflow["jobs"]["shard"]["strategy"]["matrix"]
    for model, shard in itertools.product(matrix["model"], matrix["shard"]):
        context = {"matrix": {"model": model, "shard": shard}, "env": env}
        rc = runner.job(workflow["jobs"]["shard"], context)
        assert rc == 0, runner.last.stdout[-3000:] + runner.last.stderr[-2000:]
    assert len(runner.commands) == len(matrix["model"]) * len(matrix["shard"])
    assert "--emrd-shard=1/4" in runner.commands[0] and "--emrd-episodes=1" in runner.commands[0]
    shards_summary = summary.read_text(encoding="utf-8")
    summary.write_text("", encoding="utf-8")

    assert runner.job(workflow["jobs"]["gate"], {"env": env}) == 0, runner.last.stdout
    out = runner.last.stdout
    assert out.startswith("12 episodes from 4 run director(ies)")
    assert "scout: 4/4 gates pass" in out and "FAIL" not in out
    gate_summary = summary.read_text(encoding="utf-8")
    assert "# EMRD results" in gate_summary and "thresholds.yaml" in gate_summary
    assert "aec" in gate_summary and "# EMRD results" in shards_summary

    (runner.repo / "thresholds.yaml").write_text(
        "scout:\n  baseline:\n    aec: {max: 0.5}\n", encoding="utf-8"
    )
    assert runner.job(workflow["jobs"]["gate"], {"env": env}) == 1, "a broken bound fails"
    assert "FAIL scout-baseline-aec" in runner.last.stdout
