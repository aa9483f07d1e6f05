"""--emrd-backend: the matching default per level, backend options, and ai2thor sessions that
keep one THOR controller per worker, record under their own cassette tree and replay."""

from __future__ import annotations

import json
from collections import Counter
from pathlib import Path

import pytest

from pytest_emrd.cassette import decode
from pytest_emrd.episode import protocol_version
from pytest_emrd.trajectory import Trajectory
from tests._sandbox import Sandbox

PRINT_SETTINGS = """
def test_settings(emrd_settings):
    print("BACKEND", emrd_settings.backend, "MATCHING", emrd_settings.matching,
          "OPTIONS", sorted(emrd_settings.backend_kwargs.items()))
"""


@pytest.mark.parametrize(
    ("ini", "cli", "expected"),
    [
        ("", [], "BACKEND builtin MATCHING strict OPTIONS []"),
        ("emrd_backend = ai2thor", [], "BACKEND ai2thor MATCHING lenient OPTIONS []"),
        ("", ["--emrd-backend=ai2thor"], "BACKEND ai2thor MATCHING lenient OPTIONS []"),
        ("emrd_matching = lenient", [], "BACKEND builtin MATCHING lenient OPTIONS []"),
        (
            "emrd_backend = ai2thor\nemrd_matching = strict",
            [],
            "BACKEND ai2thor MATCHING strict OPTIONS []",
        ),
        (
            "emrd_backend_option = gpu_device=1 local_executable_path=/opt/thor/thor",
            [],
            "OPTIONS [('gpu_device', 1), ('local_executable_path', '/opt/thor/thor')]",
        ),
        (
            "emrd_backend_option = gpu_device=1",
            ["--emrd-backend-option=gpu_device=2", "--emrd-backend-option=start_timeout=30"],
            "OPTIONS [('gpu_device', 2), ('start_timeout', 30)]",
        ),
    ],
    ids=[
        "default",
        "ai2thor-ini",
        "ai2thor-cli",
        "lenient-ini",
        "strict-on-ai2thor",
        "options-ini",
        "options-cli-over-ini",
    ],
)
def test_backend_settings_per_level(sandbox: Sandbox, ini, cli, expected):
    sandbox.makeini(f"[pytest]\n{ini}\n")
    sandbox.makepyfile(PRINT_SETTINGS)
    result = sandbox.runpytest("-s", "-p", "no:cacheprovider", *cli)
    result.assert_outcomes(passed=1)
    out = result.stdout.str()
    assert expected in out
    warned = "MatchingWarning: --emrd-matching=strict with --emrd-backend=ai2thor" in out
    assert warned == ("MATCHING strict" in expected and "ai2thor" in expected)


def test_a_malformed_backend_option_is_a_usage_error(sandbox: Sandbox):
    sandbox.makepyfile(PRINT_SETTINGS)
    result = sandbox.runpytest("--emrd-backend-option=gpu_device")
    assert result.ret == pytest.ExitCode.USAGE_ERROR
    result.stderr.fnmatch_lines(["*--emrd-backend-option='gpu_device' must look like KEY=VALUE*"])


def _events(log: Path) -> list[dict]:
    return [json.loads(line) for line in log.read_text().splitlines()] if log.exists() else []


def _trajectories(run_dir: Path) -> dict[str, Trajectory]:
    """Each stored trajectory (compared as trajectories: a step's wall time is no part of it)."""
    return {
        p.name: Trajectory.from_dict(json.loads(p.read_text())["trajectory"])
        for p in sorted((run_dir / "episodes").glob("*.json"))
    }


@pytest.mark.slow
def test_ai2thor_records_and_replays_with_one_controller_per_worker(thor_suite, small):
    suite, backend, log = thor_suite
    record = suite.runpytest(
        *small(*backend, f"--emrd-results={suite.path / 'recorded'}", "--emrd-record-mode=once")
    )
    record.assert_outcomes(passed=4)
    events = _events(log)
    assert [e["event"] for e in events] == ["start", "stop"], "one controller for two episodes"
    assert events[0]["gpu_device"] == 1 and events[0]["local"].endswith("thor-Linux64-local")
    tree = suite.path / "cassettes" / "ai2thor" / "scout" / "baseline" / "default" / "office"
    assert sorted(p.name for p in tree.iterdir()) == ["ep00.json.xz", "ep01.json.xz"]
    assert decode((tree / "ep00.json.xz").read_bytes()).protocol == protocol_version("ai2thor")
    assert not (suite.path / "cassettes" / "scout").exists(), "the builtin tree stays untouched"

    log.unlink()
    replay = suite.runpytest(
        *small(*backend, f"--emrd-results={suite.path / 'replayed'}", "--emrd-record-mode=none"),
        "-n",
        "2",
    )
    replay.assert_outcomes(passed=4)
    events = _events(log)
    starts = Counter(e["pid"] for e in events if e["event"] == "start")
    stops = Counter(e["pid"] for e in events if e["event"] == "stop")
    assert starts == stops and set(starts.values()) == {1} and 1 <= len(starts) <= 2
    assert _trajectories(suite.path / "replayed") == _trajectories(suite.path / "recorded")
    protocols = {t.protocol for t in _trajectories(suite.path / "replayed").values()}
    assert protocols == {protocol_version("ai2thor")}


@pytest.mark.slow
def test_builtin_results_are_not_reused_for_ai2thor(thor_suite, small, recorded):
    """The same run directory resumed on another backend recomputes: protocols differ."""
    suite, backend, log = thor_suite
    run_dir = suite.path / "run"
    builtin = suite.runpytest(
        *small(
            f"--emrd-cassettes={recorded}", "--emrd-record-mode=none", f"--emrd-results={run_dir}"
        )
    )
    builtin.assert_outcomes(passed=4)
    assert not log.exists()
    thor = suite.runpytest(
        *small(*backend, "--emrd-record-mode=once", f"--emrd-results={run_dir}", "-k", "ep00")
    )
    thor.assert_outcomes(passed=1, deselected=3)
    assert [e["event"] for e in _events(log)] == ["start", "stop"]
