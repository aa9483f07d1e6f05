"""pytest-emrd as a model team uses it: from a built wheel, in a repository of its own.

The wheel is built (``pip wheel . --no-deps``) and installed into a fresh virtualenv that
sees this machine's installed dependencies as paths (no download; nothing of this checkout,
not even through its editable install, on ``sys.path``). A temporary repository holding only
``models.yaml`` (one model, ``my-vlm``, served by ``emrd serve`` on 127.0.0.1) and
``thresholds.yaml`` then goes through the team's cycle: record the grid's episodes, replay
them with the server gone and the network blocked, gate them with ``emrd gate``, and run
examples/ci/emrd.yml as written (every shard job of the matrix, then the gate job), each job
in a fresh copy of the repository with artifacts passed between jobs as GitHub would.
"""

from __future__ import annotations

import itertools
import os
import re
import shutil
import signal
import subprocess
import sys
import sysconfig
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import pytest
import yaml
from filelock import FileLock

from tests._workflow import LocalRunner

ROOT = Path(__file__).resolve().parents[1]
WORKFLOW = ROOT / "examples" / "ci" / "emrd.yml"
MODEL = "my-vlm"

pytestmark = pytest.mark.slow

THRESHOLDS = f"""\
{MODEL}:
  baseline:
    errored_rate: {{max: 0.0}}
    never_visited: {{max: 0.0}}
  low_light:
    errored_rate: {{max: 0.0}}
"""


@dataclass(frozen=True)
class Venv:
    root: Path
    wheel: Path

    @property
    def bin(self) -> Path:
        return self.root / "bin"

    def env(self, **extra: str) -> dict[str, str]:
        """The team's shell: this virtualenv first on PATH, nothing of this checkout."""
        env = {k: v for k, v in os.environ.items() if k not in {"PYTHONPATH", "CI"}}
        env.update(PATH=f"{self.bin}{os.pathsep}{env['PATH']}", VIRTUAL_ENV=str(self.root))
        return {**env, **extra}


def _built_wheel(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The wheel of this checkout, built once per session under a file lock: setuptools builds
    in the source tree (``build/``), so two xdist workers building at once collide."""
    base = tmp_path_factory.getbasetemp()
    # An xdist worker's base lies in the session's folder; without xdist the parent is shared
    # by every session, where a wheel of an older checkout would be found.
    shared = base.parent if os.environ.get("PYTEST_XDIST_WORKER") else base
    with FileLock(shared / "emrd-wheel.lock"):
        out = shared / "emrd-wheel"
        if not any(out.glob("pytest_emrd-*.whl")):
            pip = [sys.executable, "-m", "pip", "--disable-pip-version-check"]
            subprocess.run([*pip, "wheel", str(ROOT), "--no-deps", "-q", "-w", str(out)],
                           check=True)  # fmt: skip
        (wheel,) = out.glob("pytest_emrd-*.whl")
    return wheel


@pytest.fixture(scope="module")
def venv(tmp_path_factory: pytest.TempPathFactory) -> Venv:
    tmp = tmp_path_factory.mktemp("wheel")
    wheel = _built_wheel(tmp_path_factory)
    root = tmp / "venv"
    subprocess.run([sys.executable, "-m", "venv", str(root)], check=True)
    python = root / "bin" / "python"
    # This machine's dependencies, as paths: a .pth of the base site-packages would also run
    # its editable-install finder, which imports this checkout's pytest_emrd before the wheel.
    purelib = _python(root, "import sysconfig; print(sysconfig.get_paths()['purelib'])")
    (Path(purelib) / "_base_site.pth").write_text(sysconfig.get_paths()["purelib"] + "\n")
    install = [str(python), "-m", "pip", "--disable-pip-version-check", "install", "-q"]
    subprocess.run([*install, "--no-index", "--no-deps", "--ignore-installed", str(wheel)],
                   check=True)  # fmt: skip
    return Venv(root, wheel)


def _models_yaml(reference_version: str) -> str:
    return f"""\
models:
  {MODEL}:
    provider: openai
    base_url: "${{MY_VLM_BASE_URL:-https://vlm.example.com/v1}}"
    env: [MY_VLM_BASE_URL]
    model_id: scout@{reference_version}
    api_key_env: MY_VLM_API_KEY
    api_key_required: false
    modality: both  # frames and the symbolic visible list (the scripted agent reads the list)
    price_per_mtok_in: 1.0
    price_per_mtok_out: 4.0
    timeout_s: 30
    max_retries: 1
"""


def _run(venv: Venv, args: list[str], cwd: Path, **env: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        args, cwd=cwd, env=venv.env(**env), capture_output=True, text=True, check=False
    )


def _python(root: Path, code: str) -> str:
    """``code``'s output in the virtualenv at ``root``, started outside this checkout."""
    done = subprocess.run(
        [str(root / "bin" / "python"), "-c", code], cwd=root, capture_output=True, text=True,
        env={k: v for k, v in os.environ.items() if k != "PYTHONPATH"}, check=False,
    )  # fmt: skip
    assert done.returncode == 0, done.stderr
    return done.stdout.strip()


@pytest.fixture(scope="module")
def server(venv: Venv) -> Iterator[str]:
    """``emrd serve`` from the virtualenv: the team's endpoint, ``MY_VLM_BASE_URL``."""
    proc = subprocess.Popen(
        [str(venv.bin / "emrd"), "serve", "--port", "0"],
        env=venv.env(),
        stdout=subprocess.PIPE,
        text=True,
    )
    assert proc.stdout is not None
    match = re.search(r"(http://127\.0\.0\.1:\d+/v1)", proc.stdout.readline())
    assert match, "emrd serve printed no address"
    yield match[1]
    proc.send_signal(signal.SIGINT)
    proc.wait(timeout=30)


@pytest.fixture(scope="module")
def team_repo(venv: Venv, tmp_path_factory: pytest.TempPathFactory) -> Path:
    repo = tmp_path_factory.mktemp("team") / "repo"
    repo.mkdir()
    version = _python(venv.root, "from pytest_emrd.agent import REFERENCE_VERSION as v;"
                            "print(v)")  # fmt: skip
    (repo / "models.yaml").write_text(_models_yaml(version), encoding="utf-8")
    (repo / "thresholds.yaml").write_text(THRESHOLDS, encoding="utf-8")
    return repo


SUITE = ["-m", "pytest", "--pyargs", "pytest_emrd.benchmarks", "-p", "no:cacheprovider"]


@pytest.fixture(scope="module")
def recorded(venv: Venv, team_repo: Path, server: str) -> Path:
    """The grid at one episode per spawn room, recorded against the team's endpoint."""
    args = [str(venv.bin / "python"), *SUITE, "-n", "2", "--emrd-models=models.yaml",
            f"--emrd-model={MODEL}", "--emrd-episodes=1", "--emrd-results=runs/record"]  # fmt: skip
    done = _run(venv, args, team_repo, MY_VLM_BASE_URL=server)
    assert done.returncode == 0, done.stdout[-4000:] + done.stderr[-2000:]
    assert "12 episodes" in done.stdout or "15 passed" in done.stdout, done.stdout[-2000:]
    return team_repo


def test_the_wheel_is_what_runs(venv: Venv) -> None:
    where = _python(venv.root, "import pytest_emrd.benchmarks as b; print(b.__file__)")
    assert where.startswith(str(venv.root)), where
    listed = subprocess.run(
        [sys.executable, "-m", "zipfile", "-l", str(venv.wheel)], capture_output=True, text=True
    ).stdout
    for member in ("pytest_emrd/benchmarks/test_emrd.py", "pytest_emrd/agent/models.yaml",
                   "pytest_emrd/view/page.js"):  # fmt: skip
        assert member in listed


def test_record_replay_offline_and_gate(venv: Venv, recorded: Path, server: str) -> None:
    repo = recorded
    visible = sorted(p.name for p in repo.iterdir() if not p.name.startswith("."))
    assert visible == ["cassettes", "models.yaml", "runs", "thresholds.yaml"]
    assert len(list((repo / "cassettes" / MODEL).rglob("ep00.*"))) == 12
    # Offline: CI mode replays with the network blocked; the endpoint is unset and unreachable.
    args = [str(venv.bin / "python"), *SUITE, "--emrd-models=models.yaml",
            f"--emrd-model={MODEL}", "--emrd-episodes=1", "--emrd-condition=baseline",
            "--emrd-spawn=office", "--emrd-results=runs/replay"]  # fmt: skip
    done = _run(venv, args, repo, CI="true", MY_VLM_BASE_URL="http://127.0.0.1:9/v1")
    assert done.returncode == 0, done.stdout[-4000:] + done.stderr[-2000:]
    assert "test_episode[my-vlm-baseline-office-ep00] PASSED" in done.stdout or re.search(
        r"\b2 passed\b|\b3 passed\b", done.stdout
    ), done.stdout[-2000:]
    gate = _run(venv, ["emrd", "gate", "runs/replay", "--models", "models.yaml"], repo)
    assert gate.returncode == 0, gate.stdout + gate.stderr
    assert gate.stdout.startswith("1 episodes from 1 run director(ies)"), gate.stdout
    assert f"{MODEL}: 2/2 gates pass" in gate.stdout, gate.stdout
    # The gate job's old failure: without the registry the team's model is unknown.
    bare = _run(venv, ["emrd", "gate", "runs/replay"], repo)
    assert bare.returncode == 2 and "--models FILE to `emrd gate`" in bare.stderr, bare.stderr


def test_the_ci_example_runs_in_the_team_repository(
    venv: Venv, recorded: Path, tmp_path: Path
) -> None:
    repo = tmp_path / "repo"  # what the team commits: no run directories
    shutil.copytree(recorded, repo, ignore=shutil.ignore_patterns("runs"))
    workflow = yaml.safe_load(WORKFLOW.read_text(encoding="utf-8"))
    summary = tmp_path / "step_summary.md"
    env = venv.env(CI="true", GITHUB_STEP_SUMMARY=str(summary))
    runner = LocalRunner(repo, tmp_path / "artifacts", env)
    # Not on PyPI from here: the package spec is the wheel (installed as written: pip install).
    values = {**workflow["env"], "EMRD_EPISODES": "1", "EMRD_PACKAGE": str(venv.wheel)}
    matrix = workflow["jobs"]["shard"]["strategy"]["matrix"]
    assert matrix["model"] == [MODEL]
    for model, shard in itertools.product(matrix["model"], matrix["shard"]):
        context = {"matrix": {"model": model, "shard": shard}, "env": values}
        rc = runner.job(workflow["jobs"]["shard"], context)
        assert rc == 0, runner.last.stdout[-3000:] + runner.last.stderr[-2000:]
    assert runner.commands[0].startswith("python -m pip install")
    assert (
        "--emrd-shard=1/4" in runner.commands[1]
        and "--emrd-models=models.yaml" in (runner.commands[1])
    )
    assert "# EMRD results" in summary.read_text(encoding="utf-8")
    summary.write_text("", encoding="utf-8")

    assert runner.job(workflow["jobs"]["gate"], {"env": values}) == 0, runner.last.stdout
    out = runner.last.stdout
    assert out.startswith("12 episodes from 4 run director(ies)"), out
    assert f"{MODEL}: 3/3 gates pass" in out and "FAIL" not in out, out
    assert "thresholds.yaml" in summary.read_text(encoding="utf-8")

    (runner.repo / "thresholds.yaml").write_text(
        f"{MODEL}:\n  baseline:\n    never_visited: {{min: 0.5}}\n", encoding="utf-8"
    )
    assert runner.job(workflow["jobs"]["gate"], {"env": values}) == 1, "a broken bound fails"
    assert f"FAIL {MODEL}-baseline-never_visited" in runner.last.stdout
