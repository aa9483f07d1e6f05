"""One writer per cassette (and per run directory's shard), and no leftovers from a kill."""

from __future__ import annotations

import dataclasses
import os
import signal
import subprocess
import sys
import textwrap
import threading
import time
from collections.abc import Callable
from pathlib import Path

import pytest

from pytest_emrd.cassette import SCRATCH, EpisodeRun, cassette_path, decode
from pytest_emrd.errors import CassetteError
from pytest_emrd.trajectory import EpisodeSpec, Trajectory
from tests._episodes import run_with_cassette

from .conftest import PROTOCOL, FakeRunner, FakeServer

ROOT = Path(__file__).resolve().parents[2]


def _python(code: str, *args: str) -> subprocess.Popen[str]:
    """A separate Python process running ``code`` with this checkout importable."""
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    return subprocess.Popen(
        [sys.executable, "-c", textwrap.dedent(code), *args],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=env,
    )


class _Paused(FakeRunner):
    """A live episode that stops after its first step until ``go`` is set."""

    def __init__(self, base_url: str) -> None:
        super().__init__(base_url)
        self.inside, self.go = threading.Event(), threading.Event()

    def __call__(self, spec: EpisodeSpec, *, live: bool) -> Trajectory:
        self.inside.set()
        self.go.wait(10)
        return super().__call__(spec, live=live)


def test_a_second_run_waits_for_the_writer_and_replays_its_recording(
    server: FakeServer, spec: EpisodeSpec, tmp_path: Path
) -> None:
    first, second = _Paused(server.url), FakeRunner(server.url)
    results: dict[str, object] = {}

    def run(name: str, runner: FakeRunner) -> None:
        results[name] = run_with_cassette(
            spec, runner, cassettes=tmp_path, protocol=PROTOCOL, record_mode="once"
        )

    a = threading.Thread(target=run, args=("a", first))
    b = threading.Thread(target=run, args=("b", second))
    a.start()
    assert first.inside.wait(10)
    b.start()
    time.sleep(0.3)
    assert b.is_alive() and second.calls == 0  # waiting for the writer
    first.go.set()
    a.join(10)
    b.join(10)
    one, two = results["a"], results["b"]
    assert one.recorded and not two.recorded  # type: ignore[attr-defined]
    assert two.trajectory.error is None, two.trajectory.error  # type: ignore[attr-defined]
    assert one.trajectory == two.trajectory  # type: ignore[attr-defined]
    assert len(server.seen_headers) == 4  # the episode's four requests, recorded once


class _Halves(FakeRunner):
    """``first`` requests, then ``halfway()``, then ``second`` more."""

    def __init__(self, base_url: str, first: int, second: int, halfway: Callable[[], None]) -> None:
        super().__init__(base_url)
        self.first, self.second, self.halfway = first, second, halfway

    def __call__(self, spec: EpisodeSpec, *, live: bool) -> Trajectory:
        self.steps = self.first
        super().__call__(spec, live=live)
        self.halfway()
        self.steps = self.second
        return super().__call__(spec, live=live)


def test_episodes_that_overlap_in_time_each_record_only_their_own_requests(
    server: FakeServer, spec: EpisodeSpec, tmp_path: Path
) -> None:
    """The first episode ends while the second is halfway: neither loses a request or takes
    one of the other's (as two cassettes each patching httpx would)."""
    halfway, go = threading.Event(), threading.Event()
    first_spec, second_spec = spec, dataclasses.replace(spec, episode=spec.episode + 1)
    first = _Halves(server.url, 2, 3, lambda: (halfway.set(), go.wait(10)))
    results: dict[str, EpisodeRun] = {}

    def run(name: str, episode: EpisodeSpec, runner: FakeRunner) -> None:
        results[name] = run_with_cassette(episode, runner, cassettes=tmp_path, protocol=PROTOCOL)

    thread = threading.Thread(target=run, args=("first", first_spec, first))
    thread.start()
    assert halfway.wait(10)
    second = _Halves(server.url, 2, 4, lambda: (go.set(), thread.join(10)))
    run("second", second_spec, second)
    assert not thread.is_alive()
    for name, episode, requests in (("first", first_spec, 5), ("second", second_spec, 6)):
        assert results[name].recorded, name
        recording = decode(cassette_path(tmp_path, episode).read_bytes())
        assert len(recording.requests) == requests, name
    assert len(server.seen_headers) == 11


def test_a_run_that_cannot_wait_longer_is_refused_in_one_line(
    server: FakeServer, spec: EpisodeSpec, tmp_path: Path
) -> None:
    path = cassette_path(tmp_path, spec)
    holder = _python(
        """
        import sys, time
        from pathlib import Path
        from pytest_emrd.cassette import writer_lock
        with writer_lock(Path(sys.argv[1]), Path(sys.argv[2])):
            print("held", flush=True)
            time.sleep(60)
        """,
        str(tmp_path),
        str(path),
    )
    try:
        assert holder.stdout is not None and holder.stdout.readline() == "held\n"
        with pytest.raises(CassetteError) as info:
            run_with_cassette(
                spec,
                FakeRunner(server.url),
                cassettes=tmp_path,
                protocol=PROTOCOL,
                record_mode="once",
                lock_timeout_s=0.3,
            )
    finally:
        holder.kill()
        holder.wait()
    message = str(info.value)
    assert "\n" not in message and "is being recorded by another run" in message
    assert not server.seen_headers


def test_a_write_killed_midway_leaves_nothing_git_would_commit(
    server: FakeServer, spec: EpisodeSpec, tmp_path: Path
) -> None:
    """SIGKILL between writing the new file and renaming it into place: the unfinished file
    is in the cassette folder's ignored scratch folder, and the next recording sweeps it."""
    repo = tmp_path / "repo"
    cassettes = repo / "cassettes"
    path = cassette_path(cassettes, spec)
    writer = _python(
        """
        import base64, os, sys, time
        from pathlib import Path
        from vcr.request import Request
        from pytest_emrd.cassette import EpisodePersister

        def stall(src, dst):
            print("written", flush=True)
            time.sleep(60)

        os.replace = stall
        body = b'{"messages":["' + base64.b64encode(os.urandom(200_000)) + b'"]}'
        response = {"status": {"code": 200, "message": "OK"}, "headers": {},
                    "body": {"string": b'{"choices":[]}'}}
        persister = EpisodePersister(protocol="p", fresh=True, rerecord_command="x",
                                     root=Path(sys.argv[1]))
        persister.save_cassette(sys.argv[2], {
            "requests": [Request("POST", "http://h/v1", body, {})], "responses": [response]})
        """,
        str(cassettes),
        str(path),
    )
    assert writer.stdout is not None and writer.stdout.readline() == "written\n"
    writer.send_signal(signal.SIGKILL)
    writer.wait()
    leftovers = list((cassettes / SCRATCH).rglob("*.tmp"))
    assert len(leftovers) == 1 and leftovers[0].stat().st_size > 200_000
    assert not path.exists()

    def git(*args: str) -> str:
        done = subprocess.run(["git", *args], cwd=repo, capture_output=True, text=True, check=True)
        return done.stdout

    git("init", "-q")
    assert git("add", "--dry-run", "cassettes/fake") == ""
    assert git("status", "--porcelain", "--untracked-files=all") == ""

    run = run_with_cassette(
        spec, FakeRunner(server.url), cassettes=cassettes, protocol=PROTOCOL, record_mode="once"
    )
    assert run.recorded and path.is_file()
    assert not list((cassettes / SCRATCH).rglob("*.tmp"))
    assert git("add", "--dry-run", "cassettes/fake").strip() == f"add '{path.relative_to(repo)}'"


def test_two_shards_started_at_once_on_one_run_directory_cannot_both_claim_it(
    tmp_path: Path,
) -> None:
    run_dir, go = tmp_path / "run", tmp_path / "go"
    claim = """
        import sys, time
        from pathlib import Path
        from pytest_emrd.errors import ConfigError
        from pytest_emrd.run import RunIdentity, resolve_settings, write_identity
        run_dir, go, shard = Path(sys.argv[1]), Path(sys.argv[2]), sys.argv[3]
        settings = resolve_settings({"model": ["gpt"], "shard": shard}, {}, rootdir=run_dir,
                                    env={})
        identity = RunIdentity.of(settings, "p")
        print("ready", flush=True)
        while not go.exists():
            time.sleep(0.001)
        try:
            write_identity(run_dir, identity)
        except ConfigError as exc:
            print(exc)
            sys.exit(3)
        """
    runs = [_python(claim, str(run_dir), str(go), shard) for shard in ("1/2", "2/2")]
    for run in runs:
        assert run.stdout is not None and run.stdout.readline() == "ready\n"
    go.touch()
    outcomes = sorted((run.wait(), run.communicate()[0]) for run in runs)
    assert [code for code, _ in outcomes] == [0, 3]
    assert "Give each shard its own run directory" in outcomes[1][1]
