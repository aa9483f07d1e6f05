"""A dead endpoint stops its model's recording after three unreachable episodes; the
printed resume command finishes the run once the endpoint is back."""

from __future__ import annotations

import re
import shlex
from pathlib import Path

import pytest

from pytest_emrd.agent import REFERENCE_VERSION
from pytest_emrd.cassette import SUFFIX
from pytest_emrd.plugin._endpoint import DEAD_AFTER, unreachable
from pytest_emrd.reference import ReferenceServer
from tests._sandbox import Sandbox

ROOT = Path(__file__).resolve().parents[2]


def _registry(path: Path, port: int) -> Path:
    path.write_text(
        "models:\n  my-vlm:\n    provider: openai\n"
        f"    base_url: http://127.0.0.1:{port}/v1\n    model_id: scout@{REFERENCE_VERSION}\n"
        "    api_key_env: null\n    modality: both\n    timeout_s: 5\n    max_retries: 0\n",
        encoding="utf-8",
    )
    return path


def test_what_counts_as_unreachable() -> None:
    refused = "TransportError: POST http://h/v1 failed after 1 attempt(s); last cause: "
    assert unreachable("errored", refused + "ConnectError: [Errno 111] Connection refused")
    assert unreachable("errored", refused + "ReadTimeout: timed out")
    assert not unreachable("errored", "TransportError: POST x failed with HTTP 400 (not retried)")
    assert not unreachable("terminated", None) and not unreachable("errored", None)


@pytest.mark.slow
def test_a_dead_endpoint_stops_the_model_and_the_resume_command_finishes(
    sandbox: Sandbox, unused_port: int
) -> None:
    sandbox.makepyfile(test_emrd=(ROOT / "benchmarks" / "test_emrd.py").read_text())
    models = _registry(sandbox.path / "models.yaml", unused_port)
    grid = ["-p", "no:cacheprovider", "--emrd-models=models.yaml", "--emrd-model=my-vlm",
            "--emrd-condition=baseline", "--emrd-preflight=off", "-rs"]  # fmt: skip
    # 4 spawn rooms x 15 episodes = 60 live episodes against nothing at all
    result = sandbox.runpytest(*grid, "--emrd-episodes=15", "--emrd-results=big")
    result.assert_outcomes(failed=DEAD_AFTER, skipped=60 - DEAD_AFTER)
    out = result.stdout.str()
    stop = re.findall(r"pytest-emrd: stopped calling model 'my-vlm': .*", out)
    assert stop and len(set(stop)) == 1, "one message"
    assert f"3 episodes in a row could not reach http://127.0.0.1:{unused_port}/v1" in stop[0]
    assert "resume with: pytest " in stop[0] and stop[0].rstrip().endswith("/big")

    # A 4-episode grid: stopped after 3, then resumed with the endpoint up.
    result = sandbox.runpytest(*grid, "--emrd-episodes=1", "--emrd-results=small")
    result.assert_outcomes(failed=DEAD_AFTER, skipped=1)
    command = re.search(r"resume with: (pytest .*)", result.stdout.str())[1]
    assert command.endswith("/small")
    with ReferenceServer(host="127.0.0.1", port=unused_port):
        resumed = sandbox.runpytest(*shlex.split(command)[1:])
    resumed.assert_outcomes(passed=4)
    assert "stopped calling" not in resumed.stdout.str()
    recorded = (sandbox.path / "cassettes" / "my-vlm").rglob(f"ep00{SUFFIX}")
    assert models.is_file() and len(list(recorded)) == 4
