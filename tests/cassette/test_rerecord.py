"""Re-recording never loses or mixes recordings: a drifted ``new_episodes`` episode is
recorded again whole, and an episode in another modality than its model's default has its
own cassette (real local servers, real vcrpy cassettes)."""

from __future__ import annotations

import dataclasses
import shlex
import subprocess
from pathlib import Path

import pytest

from pytest_emrd.agent import load_registry
from pytest_emrd.cassette import cassette_path, decode, found_cassette
from pytest_emrd.episode import protocol_version
from pytest_emrd.trajectory import EpisodeSpec
from tests._episodes import agent_runner, run_with_cassette

from .conftest import PROTOCOL, FakeRunner, FakeServer


def _texts(path: Path) -> list[str]:
    """The step text of the newest user message of each recorded request."""
    out = []
    for request in decode(path.read_bytes()).requests:
        body = request.body.decode()
        at = body.rindex('"Step ')
        out.append(body[at + 1 : body.index('"', at + 1)])
    return out


def test_a_drifted_new_episodes_replay_is_recorded_again_whole(server: FakeServer, spec, tmp_path):
    old = FakeRunner(server.url, steps=4)
    run_with_cassette(spec, old, cassettes=tmp_path, protocol=PROTOCOL)
    path = cassette_path(tmp_path, spec)
    assert _texts(path) == [f"Step {t} of 50" for t in (1, 2, 3, 4)]
    before = len(server.seen_headers)

    new = FakeRunner(server.url, steps=4, suffix=" (new)", suffix_from=3)
    done = run_with_cassette(
        spec, new, cassettes=tmp_path, protocol=PROTOCOL, record_mode="new_episodes"
    )

    assert done.recorded and done.trajectory.status == "budget", done.trajectory.error
    # only the new run's interactions: no stale step 3 and 4, no appended tail
    assert _texts(path) == [
        "Step 1 of 50",
        "Step 2 of 50",
        "Step 3 of 50 (new)",
        "Step 4 of 50 (new)",
    ]
    assert len(server.seen_headers) - before == 4  # the whole episode went to the model again
    replay = run_with_cassette(spec, new, cassettes=tmp_path, protocol=PROTOCOL, record_mode="none")
    assert replay.trajectory == done.trajectory


def test_new_episodes_leaves_a_cassette_that_still_matches_untouched(
    server: FakeServer, spec, tmp_path
):
    runner = FakeRunner(server.url, steps=3)
    run_with_cassette(spec, runner, cassettes=tmp_path, protocol=PROTOCOL)
    path = cassette_path(tmp_path, spec)
    recorded, before = path.read_bytes(), len(server.seen_headers)
    done = run_with_cassette(
        spec, runner, cassettes=tmp_path, protocol=PROTOCOL, record_mode="new_episodes"
    )
    assert not done.recorded and done.trajectory.status == "budget"
    assert path.read_bytes() == recorded and len(server.seen_headers) == before


def test_a_text_recording_of_a_vision_model_leaves_the_vision_cassette_alone(
    server: FakeServer, spec, tmp_path
):
    def vision_default(model: str) -> str:
        return "vision"

    runner = FakeRunner(server.url, steps=3)
    run_with_cassette(
        spec, runner, cassettes=tmp_path, protocol=PROTOCOL, modality_of=vision_default
    )
    plain = tmp_path / "fake/baseline/default/office/ep03.json.xz"  # where it always was
    kept = plain.read_bytes()
    text = dataclasses.replace(spec, modality="text")

    done = run_with_cassette(
        text,
        FakeRunner(server.url, steps=2),
        cassettes=tmp_path,
        protocol=PROTOCOL,
        record_mode="all",
        modality_of=vision_default,
    )

    assert done.recorded and done.trajectory.status == "budget", done.trajectory.error
    assert plain.read_bytes() == kept
    own = tmp_path / "fake/baseline/default+text/office/ep03.json.xz"
    assert len(_texts(own)) == 2
    # without the registry (the viewer), each episode still finds its own recording
    assert found_cassette(tmp_path, text) == own and found_cassette(tmp_path, spec) == plain


BOTH = EpisodeSpec("scout", "baseline", "office", 0, modality="both")  # its default
TEXT = dataclasses.replace(BOTH, modality="text")
REGISTRY = load_registry()


def modality_of(model: str) -> str:
    return str(REGISTRY.get(model).modality)


@pytest.fixture(scope="module")
def runner():
    run = agent_runner(REGISTRY)
    yield run
    run.close()


def _run(spec: EpisodeSpec, runner, root: Path, mode: str, **kwargs):
    return run_with_cassette(
        spec, runner, cassettes=root, protocol=protocol_version(), record_mode=mode, **kwargs
    )


def test_each_modality_of_a_reference_model_replays_from_its_own_cassette(runner, tmp_path):
    both = _run(BOTH, runner, tmp_path, "once", modality_of=modality_of)
    plain = tmp_path / "scout/baseline/default/office/ep00.json.xz"  # the committed layout
    assert both.recorded and plain.is_file(), both.trajectory.error
    kept = plain.read_bytes()

    text = _run(TEXT, runner, tmp_path, "all", modality_of=modality_of)

    assert text.recorded and text.trajectory.status != "errored", text.trajectory.error
    assert cassette_path(tmp_path, TEXT, modality_of=modality_of) == (
        tmp_path / "scout/baseline/default+text/office/ep00.json.xz"
    )
    assert plain.read_bytes() == kept
    for spec, first in ((BOTH, both), (TEXT, text)):
        again = _run(spec, runner, tmp_path, "none", modality_of=modality_of)
        assert again.trajectory == first.trajectory


def test_the_mismatch_fix_moves_the_recording_and_never_overwrites_it(runner, tmp_path):
    # a text recording where the default (both) episode lives, as older releases stored it
    text = _run(TEXT, runner, tmp_path, "once")
    plain = cassette_path(tmp_path, BOTH)
    home = cassette_path(tmp_path, TEXT, modality_of=modality_of)
    kept = plain.read_bytes()

    error = _run(BOTH, runner, tmp_path, "none", modality_of=modality_of).trajectory.error
    head = (
        f"modality mismatch: cassette={str(plain)!r} was recorded in modality 'text' and this "
        f"run shows the model 'both'. A 'text' episode belongs at {home}: move it there "
        f"({shlex.join(['mkdir', '-p', str(home.parent)])} && "
        f"{shlex.join(['mv', str(plain), str(home)])}; it then replays with "
        "--emrd-modality=text), then record the 'both' episode: "
    )
    assert (error or "").startswith(head)
    command = shlex.split((error or "")[len(head) :])
    assert "--emrd-record-mode=once" in command and "--emrd-modality=both" in command

    move = head.split("move it there (", 1)[1].split("; it then", 1)[0]
    subprocess.run(["sh", "-c", move], check=True)  # the printed fix, then its record command
    both = _run(BOTH, runner, tmp_path, "once", modality_of=modality_of)
    assert both.recorded and both.trajectory.status != "errored", both.trajectory.error
    assert home.read_bytes() == kept
    again = _run(TEXT, runner, tmp_path, "none", modality_of=modality_of)
    assert again.trajectory == text.trajectory


def test_a_stray_copy_is_re_recorded_when_the_modality_has_its_own_cassette(runner, tmp_path):
    _run(TEXT, runner, tmp_path, "once", modality_of=modality_of)
    home = cassette_path(tmp_path, TEXT, modality_of=modality_of)
    plain = cassette_path(tmp_path, BOTH)
    plain.parent.mkdir(parents=True)
    plain.write_bytes(home.read_bytes())

    error = _run(BOTH, runner, tmp_path, "none", modality_of=modality_of).trajectory.error

    assert f"The 'text' episode has its own cassette, {home} (replay it with " in (error or "")
    assert "re-record this one in 'both': pytest " in (error or "")
    assert "--emrd-record-mode=all" in (error or "")
