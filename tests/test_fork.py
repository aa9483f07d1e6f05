"""Forked workers compute what the caller would, in the caller's order."""

from __future__ import annotations

import os
import sys
import threading

import pytest

from pytest_emrd._fork import fork_map


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
def test_fork_map_forks_where_it_is_safe():
    assert threading.active_count() == 1
    pids = {pid for _, pid in fork_map(_square_and_pid, list(range(8)), 2)}
    assert os.getpid() not in pids
