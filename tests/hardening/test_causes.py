"""Probe 4: a failed replay keeps its cause. A recorded response the client cannot read, a
modality other than the recorded one and real drift are three different messages, each with
the command that fixes it (real reference server, real vcrpy cassettes)."""

from __future__ import annotations

import dataclasses
import shlex
from pathlib import Path

import pytest

from pytest_emrd.agent import load_registry
from pytest_emrd.cassette import Invocation, cassette_path, decode, encode
from pytest_emrd.cassette._paths import text_context
from pytest_emrd.episode import protocol_version
from pytest_emrd.trajectory import EpisodeSpec
from tests._episodes import agent_runner, run_with_cassette

SPEC = EpisodeSpec("scout", "baseline", "office", 0, modality="text")
HOW = Invocation(paths=("suite/test_emrd.py",), models_file=Path("my-models.yaml"))


@pytest.fixture(scope="module")
def runner():
    run = agent_runner(load_registry())
    yield run
    run.close()


@pytest.fixture(scope="module")
def recorded(tmp_path_factory: pytest.TempPathFactory, runner) -> Path:
    root = tmp_path_factory.mktemp("cassettes")
    run = run_with_cassette(SPEC, runner, cassettes=root, protocol=protocol_version())
    assert run.recorded and run.trajectory.status != "errored", run.trajectory.error
    return root


def _replay(spec: EpisodeSpec, runner, root: Path) -> str:
    run = run_with_cassette(
        spec,
        runner,
        cassettes=root,
        protocol=protocol_version(),
        record_mode="none",
        invocation=HOW,
    )
    assert run.trajectory.status == "errored"
    return run.trajectory.error or ""


def _rerecord(spec: EpisodeSpec, root: Path) -> str:
    return shlex.join(
        [
            "pytest",
            "suite/test_emrd.py",
            "--emrd-model=scout",
            "--emrd-condition=baseline",
            "--emrd-spawn=office",
            "--emrd-episodes=1",
            f"--emrd-modality={spec.modality}",
            "--emrd-models=my-models.yaml",
            f"--emrd-cassettes={root}",
            "--emrd-record-mode=all",
            "-k",
            "test_episode and scout-baseline-office-ep00",
        ]
    )


def test_an_unreadable_recorded_response_is_not_called_drift(recorded, runner, tmp_path):
    root = tmp_path / "cassettes"
    path = cassette_path(root, SPEC)
    data = decode(cassette_path(recorded, SPEC).read_bytes())
    garbage = {**data.responses[0], "body": {"string": b"<html>502 Bad Gateway</html>"}}
    data = dataclasses.replace(data, responses=(garbage, *data.responses[1:]))
    path.parent.mkdir(parents=True)
    path.write_bytes(encode(data))
    assert _replay(SPEC, runner, root) == (
        f"unreadable recorded response: response 1 of cassette={str(path)!r} (HTTP 200) was "
        "replayed and the client could not read it as a reply (it asked for the same request "
        "again); the body starts '<html>502 Bad Gateway</html>'. The file is damaged or was "
        f"recorded from another endpoint; re-record it: {_rerecord(SPEC, root)}"
    )


def test_another_modality_than_the_recorded_one_is_named(recorded, runner):
    spec = dataclasses.replace(SPEC, modality="both")
    path = cassette_path(recorded, spec)
    assert _replay(spec, runner, recorded) == (
        f"modality mismatch: cassette={str(path)!r} was recorded in modality 'text' and this "
        "run shows the model 'both'. Replay it with --emrd-modality=text, or replace it by the "
        f"'both' episode (the 'text' recording is lost): {_rerecord(spec, recorded)}"
    )


def test_drift_shows_the_context_of_the_first_difference_and_the_command(recorded, runner):
    spec = dataclasses.replace(SPEC, max_steps=49)
    error = _replay(spec, runner, recorded)
    head, _, rest = error.partition("; first differing field ")
    assert head == (
        "environment or prompt drift: request 1 of the episode matches nothing in "
        f"cassette={str(cassette_path(recorded, spec))!r}"
    )
    where, _, detail = rest.partition(" at character ")
    assert where.startswith("body.messages[")
    assert "of 49" in detail.split(", recorded")[0] and "of 50" in detail.split(", recorded")[1]
    assert error.endswith(f"If the change is intended, re-record it: {_rerecord(spec, recorded)}")


def test_text_context_centres_on_the_first_difference():
    now, then = "a" * 100 + "NEW" + "z" * 100, "a" * 100 + "OLD" + "z" * 100
    assert text_context(now, then, width=5) == (
        "at character 100 (of 203 now, 203 recorded): "
        "now ...'aaaaaNEWzz'..., recorded ...'aaaaaOLDzz'..."
    )
    assert text_context("abc", "abcd", width=5) == (
        "at character 3 (of 3 now, 4 recorded): now 'abc', recorded 'abcd'"
    )
