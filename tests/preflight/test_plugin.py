"""The plugin preflights before any live recording, once per model, on the controller only."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests._sandbox import Sandbox

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture
def bench(sandbox: Sandbox) -> Sandbox:
    sandbox.makepyfile(test_emrd=(ROOT / "benchmarks" / "test_emrd.py").read_text())
    return sandbox


def _args(*extra: str) -> list[str]:
    return [
        "-p", "no:cacheprovider", "--emrd-condition=baseline", "--emrd-spawn=office",
        "--emrd-episodes=2", *extra,
    ]  # fmt: skip


@pytest.mark.slow
@pytest.mark.parametrize("xdist", [[], ["-n", "2"]], ids=["serial", "xdist"])
def test_a_refusing_server_stops_the_live_grid_before_any_episode(
    bench, fake_vllm, registry_for, xdist
):
    fake_vllm.image_limit = 1
    models = registry_for(fake_vllm.base_url)
    result = bench.runpytest(*_args("--emrd-model=qwen3-vl-32b", f"--emrd-models={models}"), *xdist)
    assert result.ret == pytest.ExitCode.USAGE_ERROR
    result.stdout.fnmatch_lines(
        [
            "*FAIL  images*At most 1 image(s) may be provided in one prompt.*",
            "*pytest-emrd: preflight of model 'qwen3-vl-32b' failed at 'probe'*"
            "--limit-mm-per-prompt '{\"image\": 10}'*emrd check --emrd-model=qwen3-vl-32b*",
        ]
    )
    assert len(fake_vllm.requests) == 1, "one probe, once, from the controller; no episode"
    assert "emrd preflight qwen3-vl-32b:" in result.stdout.str()
    assert result.stdout.str().count("emrd preflight qwen3-vl-32b:") == 1
    assert not (bench.path / "cassettes").exists()


@pytest.mark.slow
def test_a_passing_preflight_runs_the_grid_and_a_replay_needs_none(bench, fake_vllm, registry_for):
    models = registry_for(fake_vllm.base_url)
    args = _args("--emrd-model=qwen3-vl-32b", f"--emrd-models={models}", "-k", "ep00")
    first = bench.runpytest(*args)
    first.assert_outcomes(passed=1)
    assert "PASS  probe" in first.stdout.str() and "1 episodes x <= 50 steps" in first.stdout.str()
    seen = len(fake_vllm.requests)
    replay = bench.runpytest(*args, "--emrd-record-mode=none")
    replay.assert_outcomes(passed=1)
    assert "emrd preflight" not in replay.stdout.str(), "a replay calls nobody"
    assert len(fake_vllm.requests) == seen


def test_collect_only_preflights_nothing(bench, fake_vllm, registry_for):
    models = registry_for(fake_vllm.base_url)
    result = bench.runpytest(
        *_args("--emrd-model=qwen3-vl-32b", f"--emrd-models={models}", "--collect-only")
    )
    assert result.ret == 0 and fake_vllm.requests == []


@pytest.mark.slow
def test_preflight_off_lets_the_episode_meet_the_refusal(bench, fake_vllm, registry_for):
    fake_vllm.image_limit = 1
    models = registry_for(fake_vllm.base_url)
    result = bench.runpytest(
        *_args("--emrd-model=qwen3-vl-32b", f"--emrd-models={models}", "-k", "ep00"),
        "--emrd-preflight=off",
    )
    result.assert_outcomes(failed=1)
    assert "emrd preflight" not in result.stdout.str()
    result.stdout.fnmatch_lines(["*errored*At most 1 image(s) may be provided in one prompt*"])
