"""$GITHUB_STEP_SUMMARY: the controller appends the run's Markdown once, workers never do."""

from __future__ import annotations

import pytest

from pytest_emrd.cli import main as emrd
from tests._sandbox import Sandbox

EARLIER = "## an earlier step\n\nkept as it was\n"


@pytest.mark.slow
@pytest.mark.parametrize("xdist", [[], ["-n", "2"]], ids=["serial", "xdist"])
def test_the_summary_is_appended_once(suite, small, recorded, monkeypatch, xdist):
    target = suite.path / "step_summary.md"
    target.write_text(EARLIER, encoding="utf-8")
    monkeypatch.setenv("GITHUB_STEP_SUMMARY", str(target))
    result = suite.runpytest(
        *small(f"--emrd-cassettes={recorded}", "--emrd-record-mode=none"), *xdist
    )
    result.assert_outcomes(passed=4)
    text = target.read_text(encoding="utf-8")
    assert text.startswith(EARLIER) and text.endswith("\n")
    summary = text[len(EARLIER) :]
    assert summary.count("# EMRD results") == 1
    assert "thresholds.yaml" in summary, "the gate section names the thresholds file"
    for gate in ("errored_rate", "aec"):
        assert gate in summary
    assert "scout" in summary and "baseline" in summary


def test_no_summary_without_emrd_cases(sandbox: Sandbox, monkeypatch):
    target = sandbox.path / "step_summary.md"
    monkeypatch.setenv("GITHUB_STEP_SUMMARY", str(target))
    sandbox.makepyfile("def test_plain():\n    assert 2 * 2 == 4\n")
    sandbox.runpytest("-p", "no:cacheprovider").assert_outcomes(passed=1)
    assert not target.exists()


@pytest.mark.slow
def test_emrd_gate_appends_the_summary_the_session_wrote(suite, small, recorded, monkeypatch):
    session_md, gate_md = suite.path / "session.md", suite.path / "gate.md"
    monkeypatch.setenv("GITHUB_STEP_SUMMARY", str(session_md))
    run_dir = suite.path / "run"
    result = suite.runpytest(
        *small(f"--emrd-cassettes={recorded}", "--emrd-record-mode=none"),
        f"--emrd-results={run_dir}",
    )
    result.assert_outcomes(passed=4)
    monkeypatch.setenv("GITHUB_STEP_SUMMARY", str(gate_md))
    monkeypatch.chdir(suite.path)
    assert emrd(["gate", "run", "--thresholds", "thresholds.yaml"]) == 0
    assert gate_md.read_text(encoding="utf-8") == session_md.read_text(encoding="utf-8")
