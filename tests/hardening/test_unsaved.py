"""Probe 3: paid work is never lost to the disk. A live episode whose cassette cannot be written
is kept (in the run directory's ``unsaved/`` folder and in its results), one warning line says
where, and a resumed run does not record it again. A cassette folder or results folder that
cannot be written is one line naming the path and the fix, before anything is sent."""

from __future__ import annotations

import json
from dataclasses import replace
from fnmatch import fnmatchcase
from pathlib import Path

import pytest

from pytest_emrd.cassette import SUFFIX
from tests._sandbox import Sandbox

ROOT = Path(__file__).resolve().parents[2]
CASE = "scout-baseline-office-ep00"
GRID = [
    "-p", "no:cacheprovider", "--emrd-model=scout", "--emrd-condition=baseline",
    "--emrd-spawn=office", "--emrd-episodes=1", "--emrd-modality=text", "--emrd-preflight=off",
]  # fmt: skip


@pytest.fixture
def suite(sandbox: Sandbox) -> Sandbox:
    sandbox.makepyfile(test_emrd=(ROOT / "benchmarks" / "test_emrd.py").read_text())
    return sandbox


def _output(result: pytest.RunResult) -> str:
    return result.stdout.str() + result.stderr.str()


@pytest.mark.slow
def test_an_episode_whose_cassette_cannot_be_written_is_kept_and_not_run_again(suite):
    # text is not scout's default modality: its cassettes have a folder of their own
    cassette = suite.path / f"cassettes/scout/baseline/default+text/office/ep00{SUFFIX}"
    cassette.mkdir(parents=True)  # a folder where the file goes: the save fails at the end
    run_dir = suite.path / "run"
    first = suite.runpytest(*GRID, f"--emrd-results={run_dir}")
    first.assert_outcomes(passed=1)
    fallback = run_dir / "unsaved" / f"{CASE}.json"
    traffic = run_dir / "unsaved" / f"{CASE}{SUFFIX}"
    lines = [x for x in _output(first).splitlines() if "CassetteNotSavedWarning" in x]
    assert len(lines) == 1 and lines[0].endswith(
        f"CassetteNotSavedWarning: {CASE}: the cassette cannot write {cassette}: the path is a "
        "folder where a file belongs; move that folder away (--emrd-cassettes DIR). The live "
        f"episode is kept in {fallback} and in the run directory: resume with --emrd-results "
        f"{run_dir} to reuse it without calling the model again. Its recorded cassette is "
        f"{traffic}; to replay it offline, fix the cause, then: mkdir -p {cassette.parent} && "
        f"mv {traffic} {cassette}"
    ), lines
    assert "Traceback" not in _output(first)
    kept = json.loads(fallback.read_text())
    assert kept["case_id"] == CASE and kept["cassette"] == str(cassette)
    assert kept["trajectory"]["steps"] and kept["trajectory"]["status"] != "errored"
    assert (run_dir / "episodes" / f"{CASE}.json").is_file()

    # Replay only, and still no cassette: the episode comes from the run directory.
    again = suite.runpytest(*GRID, f"--emrd-results={run_dir}", "--emrd-record-mode=none")
    again.assert_outcomes(passed=1)
    assert cassette.is_dir() and "CassetteNotSavedWarning" not in _output(again)


@pytest.mark.slow
@pytest.mark.parametrize(
    ("setup", "option", "message"),
    [
        (
            "notes.txt",
            "--emrd-cassettes={root}/notes.txt/cassettes",
            "ERROR: --emrd-cassettes={root}/notes.txt/cassettes lies under the file "
            "{root}/notes.txt; pass the cassette folder (default: <rootdir>/cassettes).",
        ),
        (
            "notes.txt",
            "--emrd-results={root}/notes.txt/run",
            "ERROR: --emrd-results={root}/notes.txt/run lies under the file {root}/notes.txt; "
            "pass a directory (a new one, or a run directory to resume).",
        ),
        (
            "run/episodes",
            "--emrd-results={root}/run",
            "*pytest-emrd: cannot write {root}/run/episodes/{case}.json: a part of the path is a "
            "file, not a folder; move that file away or use another folder (--emrd-results "
            "DIR).*",
        ),
    ],
    ids=["cassettes-under-a-file", "results-under-a-file", "episodes-folder-is-a-file"],
)
def test_a_folder_that_cannot_be_written_is_one_line(suite, setup, option, message):
    (suite.path / setup).parent.mkdir(parents=True, exist_ok=True)
    (suite.path / setup).write_text("not a folder\n")
    root = str(suite.path)
    result = suite.runpytest(*GRID, option.format(root=root))
    assert result.ret != 0
    output = _output(result)
    expected = message.format(root=root, case=CASE)
    assert len([x for x in output.splitlines() if fnmatchcase(x, expected)]) == 1, output
    assert "Traceback" not in output


def test_a_cassette_path_under_a_file_is_refused_before_the_model_is_called(tmp_path, monkeypatch):
    from pytest_emrd.episode import SimulatorPool
    from pytest_emrd.errors import CassetteError
    from pytest_emrd.plugin._endpoint import EndpointWatch
    from pytest_emrd.plugin._run import Run
    from pytest_emrd.run import resolve_settings

    (tmp_path / "notes.txt").write_text("x")
    settings = resolve_settings({"model": ["scout"]}, {}, rootdir=tmp_path, env={})
    run = Run(None, settings, tmp_path / "run", "s")  # type: ignore[arg-type]
    calls = []
    monkeypatch.setattr(SimulatorPool, "run", lambda *a, **k: calls.append(a))
    run.__dict__["invocation"] = None  # no pytest session here
    run.__dict__["endpoints"] = EndpointWatch(tmp_path / "run", "s", [])
    run.__dict__["settings"] = replace(settings, cassettes=tmp_path / "notes.txt" / "c")
    spec = run.episode_specs[0]
    with pytest.raises(CassetteError, match=r"Nothing was sent to the model\.$"):
        run.compute(spec)
    assert calls == []
