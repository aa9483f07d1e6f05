"""Parametrisation: readable sorted ids from the options, gates from thresholds.yaml."""

from __future__ import annotations

import pytest


def _ids(result: pytest.RunResult) -> list[str]:
    return [line.split("::")[1] for line in result.stdout.lines if "::test_" in line]


def test_ids_follow_the_options(suite: pytest.Pytester):
    result = suite.runpytest(
        "--collect-only",
        "-q",
        "--emrd-condition=low_light",
        "--emrd-spawn=kitchen",
        "--emrd-spawn=office",
        "--emrd-episodes=8",
    )
    ids = _ids(result)
    assert "test_episode[scout-low_light-kitchen-ep07]" in ids
    episodes = [i for i in ids if i.startswith("test_episode")]
    assert len(episodes) == 16 and episodes[0] == "test_episode[scout-low_light-office-ep00]"
    assert [i for i in ids if i.startswith("test_gate")] == []  # no gates for low_light


def test_gate_ids_per_model_condition_metric(suite: pytest.Pytester):
    result = suite.runpytest("--collect-only", "-q", "--emrd-episodes=1")
    gates = [i for i in _ids(result) if i.startswith("test_gate")]
    assert gates == ["test_gate[scout-baseline-errored_rate]", "test_gate[scout-baseline-aec]"]


def test_variant_and_several_models(suite: pytest.Pytester):
    result = suite.runpytest(
        "--collect-only",
        "-q",
        "--emrd-model=scout",
        "--emrd-model=gemini",
        "--emrd-variant=B3",
        "--emrd-episodes=1",
        "--emrd-condition=baseline",
    )
    ids = _ids(result)
    assert ids[0] == "test_episode[gemini-baseline-B3-office-ep00]"
    assert "test_gate[scout-baseline-B3-aec]" in ids


@pytest.mark.slow
def test_shard_takes_a_deterministic_slice_and_leaves_gates_to_emrd_gate(suite: pytest.Pytester):
    full = _ids(suite.runpytest("--collect-only", "-q", "--emrd-episodes=3", "-k", "test_episode"))
    parts = []
    for k in (1, 2, 3):
        result = suite.runpytest("--collect-only", "-q", "--emrd-episodes=3", f"--emrd-shard={k}/3")
        parts.append(_ids(result))
        result.stdout.fnmatch_lines(["*1 deselected*"])
    assert sorted(i for p in parts for i in p) == sorted(full)
    assert all(len(p) == len(full) // 3 for p in parts)


def test_unknown_model_lists_the_known_ones(suite: pytest.Pytester):
    result = suite.runpytest("--collect-only", "-q", "--emrd-model=gpt9")
    result.stdout.fnmatch_lines(["*pytest-emrd:*gpt9*gemini*"])
    assert result.ret != 0


def test_bad_thresholds_fail_collection_naming_file_and_line(suite: pytest.Pytester):
    suite.makefile(".yaml", thresholds="scout:\n  baseline:\n    speed: {min: 1}\n")
    result = suite.runpytest("--collect-only", "-q")
    result.stdout.fnmatch_lines(["*thresholds.yaml, line 3: unknown metric 'speed'; allowed: aec*"])
