"""Shared test configuration: hypothesis profiles, a bytecode cache for the Python processes
tests start, the order of the slow tests, a loopback JSON server.

``ci`` (the default here) is derandomized with no deadline so CI results are
reproducible and immune to a slow shared machine; ``dev`` explores more; ``explore`` (the
scheduled job of examples/ci/emrd.yml) draws new random inputs every run, many more of them,
and prints the blob that reproduces a failure.
"""

from __future__ import annotations

import json
import os
import shutil
import tempfile
import threading
from collections.abc import Callable, Iterator
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from pathlib import Path
from typing import Any

import pytest
from filelock import FileLock
from hypothesis import HealthCheck, settings

from tests._sandbox import Sandbox

#: ``answer(method, path, json_body_or_None) -> (status, payload)`` of :func:`json_server`.
Answer = Callable[[str, str, Any], tuple[int, Any]]

settings.register_profile(
    "ci",
    derandomize=True,
    deadline=None,
    max_examples=200,
    suppress_health_check=[HealthCheck.too_slow],
    print_blob=True,
)
settings.register_profile("dev", deadline=None, max_examples=500)
settings.register_profile(
    "explore",
    deadline=None,
    max_examples=2000,
    suppress_health_check=[HealthCheck.too_slow],
    print_blob=True,
)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "ci"))


def pytest_configure(config: pytest.Config) -> None:
    _cache_bytecode_of_child_processes(config)
    if not hasattr(config, "workerinput"):  # the controller, before xdist starts its workers
        _hand_out_one_test_at_a_time(config)


#: The session's bytecode cache, named by the controller for its xdist workers.
_PYCACHE = "EMRD_TESTS_PYCACHE"


def _cache_bytecode_of_child_processes(config: pytest.Config) -> None:
    """Give the Python processes the tests start one throw-away bytecode cache.

    With ``PYTHONDONTWRITEBYTECODE=1`` (a machine that keeps ``.pyc`` files out of its source
    trees), every ``pytest`` a test starts (sandbox sessions, their xdist workers, the CI
    example's shards) would compile every module of the product again and re-rewrite every
    plugin package pytest rewrites (hypothesis' among them): 1.5 to 2 s of CPU per process.
    Those processes instead read and write ``.pyc`` files under one temporary
    ``PYTHONPYCACHEPREFIX`` per session, never next to a source; the controller removes it
    when the session ends. This process and xdist's workers keep their own start-up as it is
    (the variables change after they started): compiling the whole virtualenv and standard
    library into an empty cache would cost them more than it saves. Where bytecode is written
    anyway (a fresh CI checkout) nothing changes.
    """
    cache = os.environ.get(_PYCACHE)
    if cache is None:
        if not os.environ.get("PYTHONDONTWRITEBYTECODE") or os.environ.get("PYTHONPYCACHEPREFIX"):
            return
        cache = tempfile.mkdtemp(prefix="emrd-tests-pycache-")
        config.add_cleanup(lambda: shutil.rmtree(cache, ignore_errors=True))
        if _distributes(config):  # the workers start after this and take it from here
            os.environ[_PYCACHE] = cache
            config.add_cleanup(lambda: os.environ.pop(_PYCACHE, None))
            return
    written = os.environ.pop("PYTHONDONTWRITEBYTECODE", None)

    def restore() -> None:
        os.environ.pop("PYTHONPYCACHEPREFIX", None)
        if written is not None:
            os.environ["PYTHONDONTWRITEBYTECODE"] = written

    config.add_cleanup(restore)
    os.environ["PYTHONPYCACHEPREFIX"] = cache


def _distributes(config: pytest.Config) -> bool:
    """Whether this process is an xdist controller handing tests to workers."""
    return config.pluginmanager.hasplugin("xdist") and config.getoption("dist") != "no"


def _hand_out_one_test_at_a_time(config: pytest.Config) -> None:
    """A few dozen tests of several seconds each (``slow``, sorted first by
    :func:`pytest_collection_modifyitems`) among ~1600 quick ones: xdist's ``load`` schedule
    gives each worker a first batch of a quarter of its share, which would put every slow test
    on the first worker. One test at a time (``--maxschedchunk=1``, unless given) keeps both
    workers busy to the end."""
    load = _distributes(config) and config.getoption("dist") == "load"
    if load and config.getoption("maxschedchunk") is None:
        config.option.maxschedchunk = 1


@pytest.hookimpl(trylast=True)
def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    """Tests marked ``slow`` (whole pytest sessions, recorded grids) run first: under xdist
    they then spread over the workers instead of ending the run on one of them. The order is
    otherwise kept (after pytest's own fixture-scope ordering)."""
    items.sort(key=lambda item: item.get_closest_marker("slow") is None)


@pytest.fixture
def sandbox(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, request: pytest.FixtureRequest
) -> Sandbox:
    """A throw-away root directory (also the working directory) where a test runs whole pytest
    sessions in child processes: see :class:`tests._sandbox.Sandbox`."""
    folder = tmp_path / "sandbox"
    folder.mkdir()
    monkeypatch.chdir(folder)
    return Sandbox(folder, request.node.originalname)


@pytest.fixture(scope="session")
def shared_folder(
    tmp_path_factory: pytest.TempPathFactory,
) -> Callable[[str, Callable[[Path], None]], Path]:
    """``shared_folder(name, build)``: a folder filled by ``build(folder)`` once per test
    session, however many xdist workers ask for it; the first builds it under a file lock, the
    others wait for it and reuse it. Callers must not change it (copy it first). A worker that
    finds a failed attempt runs ``build`` again, so the error shows wherever it matters.
    """
    base = tmp_path_factory.getbasetemp()
    if os.environ.get("PYTEST_XDIST_WORKER"):
        base = base.parent  # this session's folder, above each worker's own

    def get(name: str, build: Callable[[Path], None]) -> Path:
        folder = base / f"shared-{name}"
        with FileLock(f"{folder}.lock"):
            if not folder.is_dir():
                partial = base / f"shared-{name}.partial"
                shutil.rmtree(partial, ignore_errors=True)
                partial.mkdir()
                build(partial)
                partial.rename(folder)
        return folder

    return get


@pytest.fixture(autouse=True)
def _outside_ci(monkeypatch: pytest.MonkeyPatch) -> None:
    """Tests start from a developer's environment even when CI runs them (``CI=true`` would
    make every recording run of a sandbox suite replay-only); a test that is about CI sets
    the variables itself."""
    for name in ("CI", "GITHUB_STEP_SUMMARY", "GITHUB_ACTIONS"):
        monkeypatch.delenv(name, raising=False)


#: A small office inventory in the shape of ``Layout.inventory()``.
INVENTORY: dict[str, dict[str, int]] = {
    "Office": {"Desk": 2, "Chair": 2, "Laptop": 2, "Shelf": 1, "HousePlant": 1},
    "Conference Room": {"DiningTable": 1, "Chair": 8, "Television": 1},
    "Kitchen": {"Fridge": 1, "CounterTop": 2, "Sink": 1, "Microwave": 1, "Stool": 1},
    "Entrance": {"Desk": 1, "ArmChair": 2, "HousePlant": 1, "ExitDoor": 1},
}


@pytest.fixture
def inventory() -> dict[str, dict[str, int]]:
    """A small office inventory in the shape of ``Layout.inventory()`` (a fresh copy)."""
    return {room: dict(counts) for room, counts in INVENTORY.items()}


@pytest.fixture
def json_server() -> Iterator[Callable[[Answer], str]]:
    """``json_server(answer)`` starts a loopback HTTP server and returns its ``/v1`` base URL.

    ``answer(method, path, body)`` gives ``(status, payload)`` for each GET or POST (``body``
    is the decoded JSON or None); every server stops when the test ends.
    """
    running: list[tuple[ThreadingHTTPServer, threading.Thread]] = []

    def start(answer: Answer) -> str:
        class Handler(BaseHTTPRequestHandler):
            protocol_version = "HTTP/1.1"

            def log_message(self, format: str, *args: Any) -> None:
                """Silent."""

            def _reply(self, method: str) -> None:
                length = int(self.headers.get("Content-Length") or 0)
                body = json.loads(self.rfile.read(length)) if length else None
                status, payload = answer(method, self.path, body)
                data = json.dumps(payload).encode()
                self.send_response(status)
                self.send_header("Content-Type", "application/json")
                self.send_header("Content-Length", str(len(data)))
                self.end_headers()
                self.wfile.write(data)

            def do_GET(self) -> None:
                self._reply("GET")

            def do_POST(self) -> None:
                self._reply("POST")

        server = ThreadingHTTPServer(("127.0.0.1", 0), Handler)
        server.daemon_threads = True
        thread = threading.Thread(target=server.serve_forever, args=(0.05,), daemon=True)
        thread.start()
        running.append((server, thread))
        return f"http://127.0.0.1:{server.server_address[1]}/v1"

    yield start
    for server, thread in running:
        server.shutdown()
        server.server_close()
        thread.join()
