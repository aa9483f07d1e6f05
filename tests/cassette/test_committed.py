"""The committed cassettes: recorded under the current protocol, and stale ones fail loudly.

A change to the world or the prompt must never replay old traffic silently: a cassette of
another protocol is refused with the command that re-records it, and a cassette whose
protocol label matches but whose traffic came from another world fails as drift, naming the
first differing field.
"""

from __future__ import annotations

import dataclasses
import shutil
from pathlib import Path

import pytest

from pytest_emrd.agent import load_registry
from pytest_emrd.cassette import cassette_path, decode, encode
from pytest_emrd.episode import protocol_version
from pytest_emrd.errors import CassetteError
from pytest_emrd.trajectory import EpisodeSpec
from tests._episodes import agent_runner, run_with_cassette

ROOT = Path(__file__).resolve().parents[2] / "cassettes"
SPEC = EpisodeSpec("scout", "baseline", "kitchen", 4, modality="both")


def _replay(spec: EpisodeSpec, root: Path):
    runner = agent_runner(load_registry())
    try:
        return run_with_cassette(
            spec, runner, cassettes=root, protocol=protocol_version(), record_mode="none"
        )
    finally:
        runner.close()


def test_every_committed_cassette_is_of_the_current_protocol() -> None:
    files = sorted(ROOT.rglob("*.json.xz"))
    assert len(files) >= 240
    stale = [f for f in files if decode(f.read_bytes()).protocol != protocol_version()]
    assert not stale, f"{len(stale)} cassettes need re-recording, e.g. {stale[0]}"


def test_a_committed_cassette_replays_offline() -> None:
    run = _replay(SPEC, ROOT)
    assert run.trajectory.status == "terminated" and not run.recorded


def test_a_cassette_of_the_previous_protocol_is_refused_with_the_rerecord_command(
    tmp_path: Path,
) -> None:
    data = decode(cassette_path(ROOT, SPEC).read_bytes())
    target = cassette_path(tmp_path, SPEC)
    target.parent.mkdir(parents=True)
    target.write_bytes(encode(dataclasses.replace(data, protocol="builtin-3+p1")))
    with pytest.raises(CassetteError, match=r"protocol 'builtin-3\+p1'.*--emrd-record-mode=all"):
        _replay(SPEC, tmp_path)


def test_traffic_of_another_world_fails_as_drift(tmp_path: Path) -> None:
    """Same protocol label, other world (another spawn pose): the first request differs."""
    other = dataclasses.replace(SPEC, episode=5)
    target = cassette_path(tmp_path, other)
    target.parent.mkdir(parents=True)
    shutil.copy(cassette_path(ROOT, SPEC), target)
    run = _replay(other, tmp_path)
    assert run.trajectory.status == "errored"
    assert "environment or prompt drift" in (run.trajectory.error or "")
    assert "first differing field" in (run.trajectory.error or "")


def test_a_replay_sends_frames_by_digest_and_matches_as_the_recording_sent_them(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """A replay never encodes a JPEG: each request carries the frame's pixel digest where the
    recording carried its data URL. Both forms redact to the same canonical request, so the
    episode replayed with real JPEG frames, as a recording sends them, matches the same
    cassette interaction by interaction and gives the same trajectory."""
    from pytest_emrd.episode import run_episode
    from pytest_emrd.world import _jpeg

    def as_recorded(spec: EpisodeSpec, **kwargs: object):
        return run_episode(spec, **{**kwargs, "replay": False})  # type: ignore[arg-type]

    runner = agent_runner(load_registry(), run=as_recorded)
    try:
        sent_as_jpeg = run_with_cassette(
            SPEC, runner, cassettes=ROOT, protocol=protocol_version(), record_mode="none"
        )
    finally:
        runner.close()

    def never(frame: object, quality: int) -> bytes:
        raise AssertionError("a replay encoded a JPEG")

    monkeypatch.setattr(_jpeg, "encode_jpeg", never)
    by_digest = _replay(SPEC, ROOT)
    assert by_digest.trajectory.status == "terminated"
    assert by_digest.trajectory == sent_as_jpeg.trajectory
    assert len(by_digest.trajectory.steps) > 10
