"""Hostile cassettes, as a pull request could commit them: a 1 GiB xz bomb, five malformed
documents and symbolic links out of the cassette folder. Each ends in one line naming the file,
in ``emrd cassettes show`` (exit status 2) and in a replay (the episode fails, the session does
not crash); the bomb within 15 s of CPU under a 1.5 GB address-space limit."""

from __future__ import annotations

import json
import lzma
import os
import resource
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path

import pytest

from pytest_emrd.cli import main as emrd

ROOT = Path(__file__).resolve().parents[2]
GOOD = ROOT / "cassettes/scout/baseline/default/office/ep00.json.xz"
#: 156 KB of xz that inflates to 1 GiB of spaces.
BOMB = Path(__file__).with_name("data") / "bomb-1gib.json.xz"


def _edited(edit: Callable[[dict], object]) -> Callable[[], bytes]:
    def make() -> bytes:
        document = json.loads(lzma.decompress(GOOD.read_bytes()))
        edit(document)
        return lzma.compress(json.dumps(document).encode())

    return make


def _response(document: dict) -> dict:
    return document["interactions"][0]["response"]


MALFORMED = [
    pytest.param(BOMB.read_bytes, "it inflates to more than 64 MiB of text", id="bomb-1gib"),
    pytest.param(
        lambda: lzma.compress(b"[" * 200_000 + b"]" * 200_000),
        "not valid JSON (depth limit exceeded",
        id="json-nested-200k-deep",
    ),
    pytest.param(
        _edited(lambda d: d["metadata"]["emrd"].update(raw=5)),
        "cassette.metadata.emrd.raw=5 is not a list",
        id="raw-not-a-list",
    ),
    pytest.param(
        _edited(lambda d: _response(d).pop("status")),
        "cassette.interactions[0].response.status is missing",
        id="no-status",
    ),
    pytest.param(
        _edited(lambda d: _response(d)["status"].update(code="two hundred")),
        'cassette.interactions[0].response.status.code="two hundred" is not a whole number',
        id="status-code-text",
    ),
    pytest.param(
        _edited(lambda d: _response(d)["body"].update(string={"a": 1})),
        "cassette.interactions[0].response.body.string=<dict> is not text or null",
        id="body-string-an-object",
    ),
]


@pytest.mark.parametrize(("make", "problem"), MALFORMED)
def test_show_ends_a_malformed_cassette_in_one_line(make, problem, tmp_path, capsys):
    path = tmp_path / "ep00.json.xz"
    path.write_bytes(make())
    assert emrd(["cassettes", "show", str(path)]) == 2
    out, err = capsys.readouterr()
    assert out == ""
    assert err.count("\n") == 1 and err.startswith(
        f"emrd cassettes: error: file={str(path)!r} is not a replayable cassette: {problem}"
    ), err


def test_a_symlinked_cassette_is_refused_unopened(tmp_path, capsys):
    path = tmp_path / "ep00.json.xz"
    path.symlink_to("/proc/self/environ")
    assert emrd(["cassettes", "show", str(path)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "is or lies under a symbolic link" in err
    assert "PATH=" not in err


def test_a_cassette_under_a_symlinked_folder_is_refused_unopened(tmp_path, capsys, monkeypatch):
    (tmp_path / "outside").mkdir()
    (tmp_path / "outside" / "ep00.json.xz").write_bytes(GOOD.read_bytes())
    (tmp_path / "repo").mkdir()
    (tmp_path / "repo" / "scout").symlink_to(tmp_path / "outside", target_is_directory=True)
    monkeypatch.chdir(tmp_path / "repo")
    assert emrd(["cassettes", "show", "scout/ep00.json.xz"]) == 2
    out, err = capsys.readouterr()
    assert out == "" and err.count("\n") == 1 and "is or lies under a symbolic link" in err


def _limited() -> None:
    resource.setrlimit(resource.RLIMIT_AS, (1536 << 20, 1536 << 20))


def test_the_bomb_ends_in_one_line_within_15_s_under_a_1_5_gb_limit():
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    shown = subprocess.run(
        [sys.executable, "-m", "pytest_emrd.cli", "cassettes", "show", str(BOMB)],
        capture_output=True,
        text=True,
        preexec_fn=_limited,
        timeout=300,
    )
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime + after.ru_stime) - (before.ru_utime + before.ru_stime)
    assert (shown.returncode, shown.stdout) == (2, "")
    assert shown.stderr.count("\n") == 1 and "inflates to more than 64 MiB" in shown.stderr
    assert cpu < 15, f"{cpu:.1f} s of CPU"


GRID = [
    "-p", "no:cacheprovider", "--emrd-model=scout", "--emrd-condition=baseline",
    "--emrd-spawn=office", "--emrd-preflight=off",
]  # fmt: skip


def _output(result: pytest.RunResult) -> str:
    return result.stdout.str() + result.stderr.str()


@pytest.mark.slow
def test_a_replay_of_hostile_cassettes_fails_each_episode_in_one_line(sandbox, tmp_path):
    sandbox.makepyfile(test_emrd=(ROOT / "benchmarks" / "test_emrd.py").read_text())
    folder = sandbox.path / "cassettes/scout/baseline/default/office"
    folder.mkdir(parents=True)
    for index, case in enumerate(MALFORMED):
        (folder / f"ep{index:02d}.json.xz").write_bytes(case.values[0]())
    outside = tmp_path / "outside.json.xz"
    outside.write_bytes(GOOD.read_bytes())
    (folder / f"ep{len(MALFORMED):02d}.json.xz").symlink_to(outside)
    run = sandbox.runpytest(
        *GRID, f"--emrd-episodes={len(MALFORMED) + 1}", "--emrd-record-mode=none"
    )
    output = _output(run)
    run.assert_outcomes(errors=len(MALFORMED) + 1)
    assert "Traceback" not in output and "INTERNALERROR" not in output
    problems = [case.values[1] for case in MALFORMED] + ["is or lies under a symbolic link"]
    for index, problem in enumerate(problems):
        case = f"scout-baseline-office-ep{index:02d}: "
        (line,) = [x for x in run.stdout.lines if x.startswith(case)]
        assert problem in line and f"ep{index:02d}.json.xz" in line


@pytest.mark.slow
def test_a_symlinked_model_folder_is_refused_before_recording(sandbox, tmp_path):
    sandbox.makepyfile(test_emrd=(ROOT / "benchmarks" / "test_emrd.py").read_text())
    outside = tmp_path / "outside"
    outside.mkdir()
    (sandbox.path / "cassettes").mkdir()
    (sandbox.path / "cassettes/scout").symlink_to(outside, target_is_directory=True)
    run = sandbox.runpytest(*GRID, "--emrd-episodes=1", "--emrd-record-mode=once")
    run.assert_outcomes(errors=1)
    assert "Traceback" not in _output(run) and "INTERNALERROR" not in _output(run)
    assert "is or lies under a symbolic link" in _output(run)
    assert list(os.walk(outside)) == [(str(outside), [], [])]
