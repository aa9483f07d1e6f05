"""When a finished run may resume without xdist workers (the whole sessions are in
``test_run.py``)."""

from __future__ import annotations

from types import SimpleNamespace

import pytest

from pytest_emrd.plugin._resume import local_workers


def _config(*, worker: bool = False, **option: object) -> object:
    defaults = {"dist": "load", "tx": ["popen", "popen"], "collectonly": False}
    config = SimpleNamespace(option=SimpleNamespace(**{**defaults, **option}))
    if worker:
        config.workerinput = {}
    return config


@pytest.mark.parametrize(
    ("config", "expected"),
    [
        (_config(), True),  # -n 2
        (_config(dist="worksteal"), True),
        (_config(dist="no", tx=[]), False),  # no -n, or -n 0
        (_config(dist="each"), False),  # every worker runs every test
        (_config(tx=["popen//python=python3.12", "popen"]), False),  # another interpreter
        (_config(tx=["ssh=build-host"]), False),
        (_config(collectonly=True), False),
        (_config(worker=True), False),
        (SimpleNamespace(option=SimpleNamespace(collectonly=False)), False),  # no xdist
    ],
    ids=["n2", "worksteal", "no-n", "each", "python", "ssh", "collect-only", "worker", "no-xdist"],
)
def test_only_local_workers_sharing_out_the_tests_are_replaced(config, expected):
    assert local_workers(config) is expected
