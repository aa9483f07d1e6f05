"""Options: one group in --help, precedence CLI > ini > default, inert without EMRD tests."""

from __future__ import annotations

import pytest

from tests._sandbox import Sandbox

PRINT_SETTINGS = """
def test_settings(emrd_settings):
    print("EPISODES", emrd_settings.episodes, "MODE", emrd_settings.record_mode,
          "MODELS", ",".join(emrd_settings.models))
"""


def test_help_documents_every_option(sandbox: Sandbox):
    from pytest_emrd.run import OPTIONS

    result = sandbox.runpytest("--help")
    out = result.stdout.str()
    assert "pytest-emrd (Explore, Map, Remember, Decide benchmark)" in out
    for option in OPTIONS:
        assert option.flag in out and option.ini in out
    assert "Choices: none, once, new_episodes, all." in " ".join(out.split())


@pytest.mark.parametrize(
    ("ini", "cli", "expected"),
    [
        ("", [], "EPISODES 20 MODE once MODELS scout"),
        (
            "emrd_episodes = 3\nemrd_record_mode = none\nemrd_model = gpt claude",
            [],
            "EPISODES 3 MODE none MODELS gpt,claude",
        ),
        (
            "emrd_episodes = 3\nemrd_record_mode = none",
            ["--emrd-episodes=5", "--emrd-record-mode=all", "--emrd-model=gemini"],
            "EPISODES 5 MODE all MODELS gemini",
        ),
    ],
    ids=["default", "ini", "cli-over-ini"],
)
def test_precedence_per_level(sandbox: Sandbox, monkeypatch, ini, cli, expected):
    monkeypatch.delenv("CI", raising=False)
    sandbox.makeini(f"[pytest]\n{ini}\n")
    sandbox.makepyfile(PRINT_SETTINGS)
    result = sandbox.runpytest("-s", *cli)
    result.assert_outcomes(passed=1)
    result.stdout.fnmatch_lines([f"*{expected}*"])


def test_bad_option_is_a_usage_error(sandbox: Sandbox):
    sandbox.makepyfile(PRINT_SETTINGS)
    result = sandbox.runpytest("--emrd-episodes=0")
    assert result.ret == pytest.ExitCode.USAGE_ERROR
    result.stderr.fnmatch_lines(["*--emrd-episodes=0 must be a whole number >= 1*"])


def test_plugin_is_inert_without_emrd_tests(sandbox: Sandbox):
    sandbox.makepyfile("def test_plain():\n    assert 1 + 1 == 2\n")
    result = sandbox.runpytest("-p", "no:cacheprovider")
    result.assert_outcomes(passed=1)
    assert "EMRD" not in result.stdout.str()
    assert not (sandbox.path / ".emrd").exists()
