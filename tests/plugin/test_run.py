"""Whole sessions against the real episode loop: replay, xdist, gates, failures, resume."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

from pytest_emrd.cli import main as emrd

pytestmark = pytest.mark.slow


def _gate_section(result: pytest.RunResult) -> list[str]:
    lines = result.stdout.lines
    start = next(i for i, line in enumerate(lines) if "EMRD gates" in line)
    return [line for line in lines[start + 1 :] if line.startswith(("scout", "  "))]


def _episodes(run_dir: Path) -> dict[str, dict]:
    return {
        p.name: json.loads(p.read_text())["trajectory"]
        for p in sorted((run_dir / "episodes").glob("*.json"))
    }


def _gate_json(
    capsys: pytest.CaptureFixture[str], thresholds: Path, *run_dirs: Path, jobs: int = 2
) -> str:
    capsys.readouterr()
    emrd(["gate", *map(str, run_dirs), "--thresholds", str(thresholds), "--json", f"--jobs={jobs}"])
    return capsys.readouterr().out


def test_replay_is_deterministic_and_xdist_and_shards_give_the_same_gates(
    suite, small, recorded, capsys
):
    runs = {}
    for name, extra in (("serial", []), ("xdist", ["-n", "2"])):
        run_dir = suite.path / name
        result = suite.runpytest(
            *small(
                f"--emrd-cassettes={recorded}",
                "--emrd-record-mode=none",
                f"--emrd-results={run_dir}",
                *extra,
            )
        )
        result.assert_outcomes(passed=4)
        assert sorted(p.name for p in run_dir.iterdir()) == ["episodes", "run.json"]
        runs[name] = (_gate_section(result), _episodes(run_dir))
    assert runs["serial"] == runs["xdist"]
    assert "scout: 2/2 gates pass" in runs["serial"][0]
    for k in (1, 2):
        result = suite.runpytest(
            *small(
                f"--emrd-cassettes={recorded}",
                "--emrd-record-mode=none",
                f"--emrd-results={suite.path / f'shard{k}'}",
                f"--emrd-shard={k}/2",
            )
        )
        result.assert_outcomes(passed=1, deselected=1)
    thresholds = suite.path / "thresholds.yaml"
    serial = _gate_json(capsys, thresholds, suite.path / "serial")
    assert '"passed": true' in serial and '"passed": false' not in serial
    assert _gate_json(capsys, thresholds, suite.path / "serial", jobs=1) == serial
    assert _gate_json(capsys, thresholds, suite.path / "xdist") == serial
    assert _gate_json(capsys, thresholds, suite.path / "shard1", suite.path / "shard2") == serial


def test_broken_threshold_fails_the_session_with_the_table(suite, small, recorded):
    suite.makefile(".yaml", thresholds="scout:\n  baseline:\n    te: {max: 1}\n")
    result = suite.runpytest(*small(f"--emrd-cassettes={recorded}", "--emrd-record-mode=none"))
    result.assert_outcomes(passed=2, failed=1)
    result.stdout.fnmatch_lines(
        [
            "*EMRD gates*",
            "scout: 0/1 gates pass",
            "*baseline*te*<= 1*FAIL*",
            "  FAIL scout-baseline-te: value * > 1",
            "FAILED test_emrd.py::test_gate[[]scout-baseline-te[]]*",
        ]
    )


@pytest.mark.parametrize("workers", [[], ["-n", "2"]], ids=["serial", "xdist"])
def test_missing_cassettes_stop_the_run_with_one_summary(suite, small, workers):
    result = suite.runpytest(
        *small("--emrd-record-mode=none", "--emrd-cassettes=nowhere", *workers)
    )
    assert result.ret != 0
    text = result.stdout.str() + result.stderr.str()
    assert text.count("have no cassette") == 1, text
    (line,) = [line for line in text.splitlines() if "have no cassette" in line]
    assert "2 of 2 episode(s) have no cassette under " in line
    assert "missing for: scout (2). Record them all with: pytest " in line
    assert "--emrd-episodes=2 --emrd-modality=both" in line
    assert "--emrd-record-mode=once -k test_episode" in line


def test_corrupted_cassette_is_a_clear_error_naming_the_file(suite, small, recorded):
    copy = suite.path / "cassettes"
    shutil.copytree(recorded, copy)
    (copy / "scout/baseline/default/office/ep01.json.xz").write_bytes(b"garbage")
    result = suite.runpytest(
        *small(f"--emrd-cassettes={copy}", "--emrd-record-mode=none", "-k", "test_episode")
    )
    result.assert_outcomes(passed=1, errors=1, deselected=2)
    result.stdout.fnmatch_lines(
        ["*scout-baseline-office-ep01: cassette=*office/ep01.json.xz* is corrupted: not an xz*"]
    )


INTERRUPT_AFTER_FIRST = """
def pytest_runtest_logreport(report):
    if report.when == "call" and "ep00" in report.nodeid:
        raise KeyboardInterrupt
"""


def test_interrupted_run_resumes_reusing_finished_episodes(suite, small, recorded):
    def args(run_dir: Path) -> list[str]:
        return small(
            f"--emrd-cassettes={recorded}", "--emrd-record-mode=none", f"--emrd-results={run_dir}"
        )

    run_dir = suite.path / "run"
    suite.makeconftest(INTERRUPT_AFTER_FIRST)
    first = suite.runpytest(*args(run_dir))
    assert first.ret == pytest.ExitCode.INTERRUPTED
    done = run_dir / "episodes" / "scout-baseline-office-ep00.json"
    assert [p.name for p in (run_dir / "episodes").iterdir()] == [done.name]
    before = (done.stat().st_mtime_ns, json.loads(done.read_text())["head"]["session"])
    suite.makeconftest("")
    second = suite.runpytest(*args(run_dir))
    second.assert_outcomes(passed=4)
    assert (done.stat().st_mtime_ns, json.loads(done.read_text())["head"]["session"]) == before
    assert len(list((run_dir / "episodes").iterdir())) == 2
    uninterrupted = suite.runpytest(*args(suite.path / "whole"))
    uninterrupted.assert_outcomes(passed=4)
    assert _gate_section(second) == _gate_section(uninterrupted)
