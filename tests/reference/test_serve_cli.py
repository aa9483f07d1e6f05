"""``emrd serve`` in the foreground, as a user runs it."""

from __future__ import annotations

import re
import subprocess
import sys

import httpx
import pytest

from pytest_emrd.agent import REFERENCE_VERSION
from pytest_emrd.cli import main


def test_emrd_serve_answers_until_interrupted() -> None:
    proc = subprocess.Popen(
        [sys.executable, "-c", "from pytest_emrd.cli import main; main()", "serve", "--port", "0"],
        stdout=subprocess.PIPE,
        text=True,
    )
    try:
        assert proc.stdout is not None
        line = proc.stdout.readline()
        match = re.search(r"(http://127\.0\.0\.1:\d+/v1)", line)
        assert match, line
        models = httpx.get(f"{match[1]}/models", timeout=10).json()
        assert f"scout@{REFERENCE_VERSION}" in {m["id"] for m in models["data"]}
    finally:
        proc.terminate()
        proc.wait(timeout=10)


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["serve", "--port", "70000"], "--port=70000 must lie in"),
        (["serve", "--host", "203.0.113.1"], "cannot be bound"),
    ],
    ids=["port-range", "unbindable-host"],
)
def test_bad_serve_arguments(argv, message, capsys) -> None:
    assert main(argv) == 2
    assert message in capsys.readouterr().err
