"""Forked workers compute what the caller would, in the caller's order."""

from __future__ import annotations

import os
import subprocess
import sys
import threading
from pathlib import Path

import pytest

from pytest_emrd._fork import fork_map

ROOT = Path(__file__).resolve().parents[1]


def _square_and_pid(n: int) -> tuple[int, int]:
    return n * n, os.getpid()


@pytest.mark.parametrize("processes", [1, 2, 3])
def test_fork_map_keeps_order_and_values(processes):
    results = fork_map(_square_and_pid, list(range(37)), processes)
    assert [value for value, _ in results] == [n * n for n in range(37)]


def test_fork_map_runs_in_other_processes_only_when_asked():
    assert {pid for _, pid in fork_map(_square_and_pid, [1, 2, 3], 1)} == {os.getpid()}
    assert fork_map(_square_and_pid, [], 2) == []
    assert fork_map(_square_and_pid, [4], 2) == [(16, os.getpid())]


@pytest.mark.skipif(sys.platform != "linux", reason="forking is used on Linux only")
def test_fork_map_forks_in_a_process_with_one_thread():
    # A fresh interpreter: a test process may hold other tests' server threads.
    code = (
        "import os\n"
        "from tests.test_fork import _square_and_pid\n"
        "from pytest_emrd._fork import fork_map\n"
        "pids = {pid for _, pid in fork_map(_square_and_pid, list(range(8)), 2)}\n"
        "print(os.getpid() in pids)\n"
    )
    done = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True, cwd=ROOT
    )
    assert done.stdout.split() == ["False"]  # how the chunks spread over workers is the OS's


def test_fork_map_computes_here_while_another_thread_runs():
    stop = threading.Event()
    other = threading.Thread(target=stop.wait)
    other.start()
    try:
        pids = {pid for _, pid in fork_map(_square_and_pid, list(range(8)), 2)}
    finally:
        stop.set()
        other.join()
    assert pids == {os.getpid()}
