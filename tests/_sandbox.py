"""Whole pytest sessions in a child process, in a throw-away root directory.

The tests of the plugin run ``pytest`` as its users do: a fresh process with its own
``sys.modules``, started in a folder holding the test files. Nothing of the child session
is imported into the test's own process, so a test can import whatever it checks with.
"""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest


class Sandbox:
    """A root directory for pytest sessions, and the command that runs one there.

    ``path`` is the folder (also the working directory of the test); ``make*`` write files
    into it (dedented, as pytester does); :meth:`runpytest` runs ``python -m pytest`` in a
    child process and returns pytest's :class:`pytest.RunResult`.
    """

    def __init__(self, path: Path, name: str) -> None:
        self.path = path
        self._name = name
        self._runs = 0

    def makefile(self, ext: str, *text: str, **files: str) -> Path:
        """Write ``NAME + ext`` for each keyword (a positional text is named after the test);
        returns the first file written."""
        named = [(self._name, body) for body in text] + list(files.items())
        written = []
        for name, body in named:
            target = self.path / f"{name}{ext}"
            target.parent.mkdir(parents=True, exist_ok=True)
            target.write_text(textwrap.dedent(body).strip() + "\n", encoding="utf-8")
            written.append(target)
        return written[0]

    def makepyfile(self, *text: str, **files: str) -> Path:
        return self.makefile(".py", *text, **files)

    def makeconftest(self, text: str) -> Path:
        return self.makefile(".py", conftest=text)

    def makeini(self, text: str) -> Path:
        return self.makefile(".ini", tox=text)

    def run(
        self, *command: str | os.PathLike[str], timeout: float | None = None
    ) -> pytest.RunResult:
        """Run ``command`` in :attr:`path` with this folder first on ``PYTHONPATH``."""
        env = dict(os.environ)
        env["PYTHONPATH"] = os.pathsep.join(filter(None, [str(self.path), env.get("PYTHONPATH")]))
        env["HOME"] = env["USERPROFILE"] = str(self.path)  # no user configuration leaks in
        env["PY_COLORS"] = "0"
        env.pop("PYTEST_ADDOPTS", None)
        start = time.perf_counter()
        done = subprocess.run(
            [os.fspath(part) for part in command],
            cwd=self.path,
            env=env,
            capture_output=True,
            text=True,
            timeout=timeout,
        )
        return pytest.RunResult(
            done.returncode,
            done.stdout.splitlines(),
            done.stderr.splitlines(),
            time.perf_counter() - start,
        )

    def runpytest(self, *args: str, timeout: float | None = None) -> pytest.RunResult:
        """``python -m pytest ARGS`` in a child process, with its own temporary folder."""
        self._runs += 1
        basetemp = self.path / f"runpytest-{self._runs}"
        return self.run(
            sys.executable, "-m", "pytest", f"--basetemp={basetemp}", *args, timeout=timeout
        )
