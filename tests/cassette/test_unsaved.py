"""A recorded episode whose cassette cannot be written keeps its recording: the cassette's
bytes come back with the run (redacted as the file would be), and replay once moved into place."""

from __future__ import annotations

import errno
import lzma
import os
import shutil
from collections.abc import Callable
from pathlib import Path

import httpx
import pytest
from vcr.request import Request

from pytest_emrd.cassette import (
    SCRATCH,
    EpisodePersister,
    EpisodeRun,
    cassette_path,
    decode,
)
from pytest_emrd.trajectory import EpisodeSpec, Trajectory
from tests._episodes import run_with_cassette, traffic

from .conftest import FAKE_KEY, PROTOCOL, FakeRunner, FakeServer


def _folder_in_the_way(path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    path.mkdir(parents=True)


def _folder_is_a_file(path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    path.parent.parent.mkdir(parents=True, exist_ok=True)
    path.parent.write_text("not a folder\n")


def _disk_full(path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    def replace(src: object, dst: object) -> None:
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), str(dst))

    monkeypatch.setattr(os, "replace", replace)


SABOTAGES: dict[str, tuple[Callable[[Path, pytest.MonkeyPatch], None], int]] = {
    "folder-in-the-way": (_folder_in_the_way, errno.EISDIR),
    "folder-is-a-file": (_folder_is_a_file, errno.EEXIST),
    "disk-full": (_disk_full, errno.ENOSPC),
}


class SabotagedRunner(FakeRunner):
    """A :class:`FakeRunner` whose cassette becomes unwritable while its episode runs."""

    def __init__(self, base_url: str, sabotage: Callable[[], None]) -> None:
        super().__init__(base_url)
        self.sabotage = sabotage

    def __call__(self, spec: EpisodeSpec, *, live: bool) -> Trajectory:
        self.sabotage()
        return super().__call__(spec, live=live)


def _record(
    spec: EpisodeSpec, runner: FakeRunner, root: Path, mode: str = "once", *, keep: bool = True
) -> EpisodeRun:
    return run_with_cassette(
        spec, runner, cassettes=root, protocol=PROTOCOL, record_mode=mode, keep_unsaved=keep
    )


@pytest.mark.parametrize("cause", list(SABOTAGES))
def test_a_cassette_that_cannot_be_written_comes_back_with_the_run(
    server: FakeServer,
    spec: EpisodeSpec,
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    cause: str,
) -> None:
    sabotage, code = SABOTAGES[cause]
    saved = _record(spec, FakeRunner(server.url), tmp_path / "good")
    root = tmp_path / "bad"
    path = cassette_path(root, spec)
    runner = SabotagedRunner(server.url, lambda: sabotage(path, monkeypatch))

    run = _record(spec, runner, root)
    monkeypatch.undo()

    assert run.trajectory.status == "budget" and run.recorded and saved.unsaved is None
    assert run.unsaved is not None and run.unsaved.path == path
    assert run.unsaved.cause.errno == code
    assert traffic(run.unsaved.blob) == traffic(cassette_path(tmp_path / "good", spec).read_bytes())
    data = decode(run.unsaved.blob)
    assert data.protocol == PROTOCOL and len(data.requests) == runner.steps
    assert FAKE_KEY.encode() not in lzma.decompress(run.unsaved.blob)
    assert not path.is_file() and list((root / SCRATCH).rglob("*.tmp")) == []


def test_the_unsaved_cassette_moved_into_place_replays_with_no_request(
    server: FakeServer, spec: EpisodeSpec, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    path = cassette_path(tmp_path, spec)
    runner = SabotagedRunner(server.url, lambda: _folder_in_the_way(path, monkeypatch))
    run = _record(spec, runner, tmp_path)
    assert run.unsaved is not None
    sent = len(server.seen_headers)

    path.rmdir()  # the cause fixed; the kept cassette moved to where it belongs
    path.write_bytes(run.unsaved.blob)
    again = _record(spec, FakeRunner(server.url), tmp_path, mode="none")

    assert again.trajectory == run.trajectory and not again.recorded
    assert again.unsaved is None and len(server.seen_headers) == sent


def test_http_is_unpatched_after_a_cassette_that_could_not_be_written(
    server: FakeServer, spec: EpisodeSpec, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    path = cassette_path(tmp_path, spec)
    runner = SabotagedRunner(server.url, lambda: _folder_is_a_file(path, monkeypatch))
    assert _record(spec, runner, tmp_path).unsaved is not None
    sent = len(server.seen_headers)
    reply = httpx.post(f"{server.url}/v1/chat/completions", json={"messages": []}, timeout=5)
    assert reply.status_code == 200 and len(server.seen_headers) == sent + 1


def test_a_caller_that_does_not_keep_unsaved_cassettes_gets_the_error(
    server: FakeServer, spec: EpisodeSpec, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    path = cassette_path(tmp_path, spec)
    runner = SabotagedRunner(server.url, lambda: _folder_in_the_way(path, monkeypatch))
    with pytest.raises(IsADirectoryError):
        _record(spec, runner, tmp_path, keep=False)
    assert runner.calls == 1 and list((tmp_path / SCRATCH).rglob("*.tmp")) == []


def test_a_persister_not_asked_to_keep_unsaved_cassettes_raises(tmp_path: Path) -> None:
    path = tmp_path / "ep00.json.xz"
    path.mkdir()
    persister = EpisodePersister(protocol="p", fresh=True, rerecord_command="x", root=tmp_path)
    response = {"status": {"code": 200, "message": "OK"}, "headers": {}, "body": {"string": b"{}"}}
    cassette = {"requests": [Request("POST", "http://h/v1", b"{}", {})], "responses": [response]}
    with pytest.raises(IsADirectoryError):
        persister.save_cassette(path, cassette)
    assert persister.unsaved is None
    shutil.rmtree(path)
    persister.save_cassette(path, cassette)
    assert decode(path.read_bytes()).protocol == "p"
