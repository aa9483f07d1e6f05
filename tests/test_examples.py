"""examples/own_repo: the fixtures in a user's own repository, run as a black box."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests._sandbox import Sandbox

ROOT = Path(__file__).resolve().parents[1]
EXAMPLE = ROOT / "examples" / "own_repo" / "test_my_agent.py"


def _run(sandbox: Sandbox, source: str) -> pytest.RunResult:
    sandbox.makepyfile(test_my_agent=source)
    assert not (sandbox.path / "thresholds.yaml").exists(), "a user repo without gates"
    return sandbox.runpytest(
        "-p", "no:cacheprovider", f"--emrd-cassettes={ROOT / 'cassettes'}",
        "--emrd-record-mode=none", "--emrd-model=scout", "--emrd-condition=baseline",
        "--emrd-spawn=office",
        "--emrd-episodes=3", "-v",
    )  # fmt: skip


@pytest.mark.slow
def test_the_example_runs_in_a_repo_without_thresholds(sandbox: Sandbox):
    result = _run(sandbox, EXAMPLE.read_text(encoding="utf-8"))
    result.assert_outcomes(passed=4)
    result.stdout.fnmatch_lines(
        [
            "*test_the_gathering_room_was_entered[[]scout-baseline-office-ep00[]] PASSED*",
            "*test_action_success_gate[[]baseline[]] PASSED*",
        ]
    )


@pytest.mark.slow
def test_the_custom_gate_fails_with_its_numbers(sandbox: Sandbox):
    source = EXAMPLE.read_text(encoding="utf-8").replace(
        "MIN_ACTION_SUCCESS = 0.6", "MIN_ACTION_SUCCESS = 1.01"
    )
    result = _run(sandbox, source)
    result.assert_outcomes(passed=3, failed=1)
    result.stdout.fnmatch_lines(
        ["*scout/baseline: action success *, 95% CI [[]*[]], n=3; the gate needs*>= 1.01"]
    )


def test_the_packaged_suite_prints_commands_that_run_as_printed(sandbox: Sandbox):
    """``pytest --pyargs pytest_emrd.benchmarks`` in a repository without the suite: a missing
    cassette names a record command that carries ``--pyargs`` (it would find no file else)."""
    result = sandbox.runpytest(
        "--pyargs", "pytest_emrd.benchmarks", "-p", "no:cacheprovider", "--emrd-model=scout",
        "--emrd-condition=baseline", "--emrd-spawn=office", "--emrd-episodes=1",
        "--emrd-record-mode=none",
    )  # fmt: skip
    assert result.ret == pytest.ExitCode.USAGE_ERROR
    result.stderr.fnmatch_lines(["*pytest --pyargs pytest_emrd.benchmarks --emrd-model=scout*"])
