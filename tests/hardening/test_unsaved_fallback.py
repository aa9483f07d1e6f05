"""Probe 3 end to end: a live episode whose cassette folder stops being writable mid-episode
keeps its result and its recorded traffic under ``<run>/unsaved/``, with its real retry
count and no planted secret; one warning line says where and how to put the cassette in
place; a resumed run does not call the model again; and the kept cassette, moved where the
warning says, replays offline without a single request."""

from __future__ import annotations

import json
import subprocess
import threading
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from pathlib import Path
from typing import Any

import httpx
import pytest

from pytest_emrd.cassette import SUFFIX, decode
from pytest_emrd.reference import reference_base_url
from pytest_emrd.run import read_episode
from tests._sandbox import Sandbox

from .conftest import Provider, leaks, leaky_registry, text_leaks

ROOT = Path(__file__).resolve().parents[2]
CASE = "leaky-baseline-office-ep00"
GRID = [
    "-p", "no:cacheprovider", "--emrd-model=leaky", "--emrd-condition=baseline",
    "--emrd-spawn=office", "--emrd-episodes=1", "--emrd-preflight=off",
]  # fmt: skip


@dataclass
class Saboteur:
    """A provider on 127.0.0.1 in front of the reference server. Its first reply is an
    empty 200 (the client retries it), sent after ``first`` ran (the sabotage)."""

    port: int
    first: Callable[[], None] = lambda: None
    requests: list[bytes] = field(default_factory=list)


@pytest.fixture
def saboteur() -> Iterator[Saboteur]:
    upstream = reference_base_url()
    state = Saboteur(port=0)

    class Handler(BaseHTTPRequestHandler):
        def log_message(self, *args: Any) -> None:
            pass

        def do_POST(self) -> None:
            body = self.rfile.read(int(self.headers["Content-Length"]))
            state.requests.append(body)
            payload = b""
            if len(state.requests) == 1:
                state.first()
            else:
                payload = httpx.post(
                    f"{upstream}/chat/completions", content=body, timeout=30
                ).content
            self.send_response(200)
            self.send_header("Content-Type", "application/json")
            self.send_header("Content-Length", str(len(payload)))
            self.end_headers()
            self.wfile.write(payload)

    httpd = ThreadingHTTPServer(("127.0.0.1", 0), Handler)
    state.port = httpd.server_address[1]
    thread = threading.Thread(target=httpd.serve_forever, daemon=True)
    thread.start()
    yield state
    httpd.shutdown()
    httpd.server_close()


def _output(result: pytest.RunResult) -> str:
    return result.stdout.str() + result.stderr.str()


@pytest.mark.slow
def test_a_cassette_folder_that_breaks_mid_episode_loses_nothing(
    sandbox: Sandbox, saboteur: Saboteur, planted_env: str
) -> None:
    sandbox.makepyfile(test_emrd=(ROOT / "benchmarks" / "test_emrd.py").read_text())
    registry = leaky_registry(
        sandbox.path / "user-models.yaml", Provider(saboteur.port), leaky="ok"
    )
    models = json.loads(registry.read_text())
    models["models"]["leaky"]["max_retries"] = 2
    registry.write_text(json.dumps(models))
    cassette = sandbox.path / f"cassettes/leaky/baseline/default/office/ep00{SUFFIX}"
    folder, run_dir = cassette.parent, sandbox.path / "run"

    def break_the_folder() -> None:  # its folder becomes a file while the episode runs
        folder.parent.mkdir(parents=True, exist_ok=True)
        folder.write_text("not a folder\n")

    saboteur.first = break_the_folder
    options = (*GRID, f"--emrd-models={registry}")
    first = sandbox.runpytest(*options, f"--emrd-results={run_dir}")
    first.assert_outcomes(passed=1)
    kept_result, kept_cassette = (
        run_dir / f"unsaved/{CASE}.json",
        run_dir / f"unsaved/{CASE}{SUFFIX}",
    )
    (line,) = [x for x in _output(first).splitlines() if "CassetteNotSavedWarning" in x]
    command = f"mkdir -p {folder} && mv {kept_cassette} {cassette}"
    assert (
        f"the cassette cannot write {cassette}: a file is in the way where a folder belongs; "
        "move it away or use another folder (--emrd-cassettes DIR). The live episode is kept in "
        f"{kept_result}" in line
    ), line
    assert line.endswith(f"Its recorded cassette is {kept_cassette}; to replay it offline, fix "
                         f"the cause, then: {command}"), line  # fmt: skip
    assert "Traceback" not in _output(first)

    # The result, with its one retry, and the cassette as it would have been written.
    kept = json.loads(kept_result.read_text())
    steps = len(kept["trajectory"]["steps"])
    assert kept["retries"] == 1 and kept["cassette"] == str(cassette)
    assert kept["interactions"] == str(kept_cassette) and kept["trajectory"]["status"] != "errored"
    assert len(saboteur.requests) == steps + 1  # the empty reply was retried once
    data = decode(kept_cassette.read_bytes())
    assert len(data.requests) == steps  # the reply that could not be read is not kept
    assert all(json.loads(r["body"]["string"])["choices"] for r in data.responses)
    assert read_episode(run_dir / f"episodes/{CASE}.json").head.retries == 1
    assert leaks(sandbox.path, skip=(registry,)) == []
    assert text_leaks(_output(first)) == []

    # Resumed: the episode comes from the run directory, the model is not called again.
    resumed = sandbox.runpytest(*options, f"--emrd-results={run_dir}")
    resumed.assert_outcomes(passed=1)
    assert len(saboteur.requests) == steps + 1 and "CassetteNotSavedWarning" not in _output(resumed)

    # The cause fixed and the command run: a new run replays offline, with no retry.
    folder.unlink()
    subprocess.run(command, shell=True, check=True)
    replay_dir = sandbox.path / "replay"
    replay = sandbox.runpytest(*options, f"--emrd-results={replay_dir}", "--emrd-record-mode=none")
    replay.assert_outcomes(passed=1)
    assert len(saboteur.requests) == steps + 1
    replayed = read_episode(replay_dir / f"episodes/{CASE}.json")
    original = read_episode(run_dir / f"episodes/{CASE}.json")
    assert replayed.trajectory == original.trajectory
    assert replayed.head.retries == 0 and not replayed.head.recorded
