"""Recording and replaying one episode through its cassette, against a real local server."""

from __future__ import annotations

import lzma
from pathlib import Path

import pytest

from pytest_emrd.cassette import LATENCY, cassette_path, decode
from pytest_emrd.errors import CassetteError
from tests._episodes import run_with_cassette

from .conftest import FAKE_KEY, PROTOCOL, FakeRunner, FakeServer


def _run(spec, runner, root: Path, mode: str, matching: str = "strict", protocol: str = PROTOCOL):
    return run_with_cassette(
        spec, runner, cassettes=root, protocol=protocol, record_mode=mode, matching=matching
    )


def test_record_then_replay_offline_gives_the_same_trajectory(server: FakeServer, spec, tmp_path):
    first = _run(spec, FakeRunner(server.url), tmp_path, "once")
    assert first.recorded and first.trajectory.status == "budget"
    path = cassette_path(tmp_path, spec)
    assert path == tmp_path / "fake/baseline/default/office/ep03.json.xz"
    requests_live = len(server.seen_headers)
    again = _run(spec, FakeRunner(server.url), tmp_path, "none")
    assert len(server.seen_headers) == requests_live  # nothing reached the server
    assert not again.recorded
    assert again.trajectory == first.trajectory


def test_each_recorded_reply_keeps_its_latency(server: FakeServer, spec, tmp_path):
    _run(spec, FakeRunner(server.url), tmp_path, "once")
    data = decode(cassette_path(tmp_path, spec).read_bytes())
    latencies = [r[LATENCY] for r in data.responses]
    assert latencies and all(isinstance(s, float) and 0 <= s < 60 for s in latencies)


def test_secrets_never_reach_the_file(server: FakeServer, spec, tmp_path):
    _run(spec, FakeRunner(server.url), tmp_path, "once")
    assert server.seen_headers[0]["Authorization"] == f"Bearer {FAKE_KEY}"
    text = lzma.decompress(cassette_path(tmp_path, spec).read_bytes()).decode()
    assert FAKE_KEY not in text
    assert "base64," not in text and "pixels:" in text


def test_changed_jpeg_quality_replays_by_pixel_digest(server: FakeServer, spec, tmp_path):
    _run(spec, FakeRunner(server.url, quality=90), tmp_path, "once")
    replay = _run(spec, FakeRunner(server.url, quality=40), tmp_path, "none")
    assert replay.trajectory.status == "budget"


def test_prompt_drift_names_the_first_differing_field(server: FakeServer, spec, tmp_path):
    _run(spec, FakeRunner(server.url), tmp_path, "once")
    drifted = _run(spec, FakeRunner(server.url, suffix=" (hurry)"), tmp_path, "none")
    error = drifted.trajectory.error or ""
    assert drifted.trajectory.status == "errored"
    assert "environment or prompt drift" in error
    assert "body.messages[1].content[0].text" in error and "hurry" in error


def test_changed_pixels_drift_strict_but_warn_lenient(server: FakeServer, spec, tmp_path):
    _run(spec, FakeRunner(server.url), tmp_path, "once")
    strict = _run(spec, FakeRunner(server.url, pixel_shift=1), tmp_path, "none")
    assert "image_url.url" in (strict.trajectory.error or "")
    lenient = _run(spec, FakeRunner(server.url, pixel_shift=1), tmp_path, "none", "lenient")
    assert lenient.trajectory.status == "budget"
    assert lenient.frame_drift == 4


def test_missing_cassette_in_none_mode_names_file_and_command(server: FakeServer, spec, tmp_path):
    run = _run(spec, FakeRunner(server.url), tmp_path, "none")
    error = run.trajectory.error or ""
    assert not server.seen_headers
    assert str(cassette_path(tmp_path, spec)) in error
    assert (
        "--emrd-record-mode=once" in error
        and "-k 'test_episode and fake-baseline-office-ep03'" in error
    )
    assert not cassette_path(tmp_path, spec).exists()


def test_corrupted_cassette_is_an_error_naming_the_file(server: FakeServer, spec, tmp_path):
    path = cassette_path(tmp_path, spec)
    path.parent.mkdir(parents=True)
    path.write_bytes(b"\xfd7zXZ\x00 not really xz")
    with pytest.raises(CassetteError, match=r"ep03\.json\.xz.*corrupted"):
        _run(spec, FakeRunner(server.url), tmp_path, "once")


def test_stale_protocol_asks_for_the_rerecord_command(server: FakeServer, spec, tmp_path):
    _run(spec, FakeRunner(server.url), tmp_path, "once")
    with pytest.raises(CassetteError, match=r"protocol 'test-protocol-1'.*--emrd-record-mode=all"):
        _run(spec, FakeRunner(server.url), tmp_path, "none", protocol="test-protocol-2")


def test_failed_episode_leaves_no_half_cassette(server: FakeServer, spec, tmp_path):
    server.fail_next = 1
    run = _run(spec, FakeRunner(server.url), tmp_path, "once")
    assert run.trajectory.status == "errored" and "500" in (run.trajectory.error or "")
    assert not cassette_path(tmp_path, spec).exists()


def test_all_mode_rerecords_from_scratch(server: FakeServer, spec, tmp_path):
    _run(spec, FakeRunner(server.url, steps=4), tmp_path, "once")
    _run(spec, FakeRunner(server.url, steps=2), tmp_path, "all")
    replay = _run(spec, FakeRunner(server.url, steps=2), tmp_path, "none")
    assert replay.trajectory.status == "budget" and len(replay.trajectory.steps) == 2
    longer = _run(spec, FakeRunner(server.url, steps=3), tmp_path, "none")
    assert "holds only 2 request(s)" in (longer.trajectory.error or "")
