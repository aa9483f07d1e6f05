"""Runs a GitHub Actions workflow's jobs locally: each job in a fresh copy of a repository,
``${{ matrix.* }}`` and ``${{ env.* }}`` substituted, artifacts passed between jobs."""

from __future__ import annotations

import re
import shutil
import subprocess
from pathlib import Path
from typing import Any

EXPRESSION = re.compile(r"\$\{\{\s*(?P<expr>[^}]*?)\s*\}\}")


def _substitute(text: str, context: dict[str, dict[str, str]]) -> str:
    def value(match: re.Match[str]) -> str:
        scope, _, name = match["expr"].partition(".")
        if scope not in context or name not in context[scope]:
            raise AssertionError(f"the local runner does not know ${{{{ {match['expr']} }}}}")
        return str(context[scope][name])

    return EXPRESSION.sub(value, text)


class LocalRunner:
    """Runs each job of a workflow in a fresh copy of ``repo`` (a new runner machine), with
    artifacts kept in ``store`` between jobs. Checkout and set-up are no-ops (the copy, the
    virtualenv); ``run:`` steps go through bash with ``${{ matrix.* }}`` and ``${{ env.* }}``
    substituted; upload/download-artifact copy folders."""

    def __init__(self, repo: Path, store: Path, env: dict[str, str]) -> None:
        self.repo, self.store, self.env = repo, store, env
        self.commands: list[str] = []
        self.jobs = 0

    def job(self, job: dict[str, Any], context: dict[str, dict[str, str]]) -> int:
        self.jobs += 1
        self.checkout = self.store.parent / f"job-{self.jobs}"
        shutil.copytree(self.repo, self.checkout, symlinks=True)
        for step in job["steps"]:
            if (rc := self.step(step, context)) != 0:
                return rc
        return 0

    def step(self, step: dict[str, Any], context: dict[str, dict[str, str]]) -> int:
        with_ = {k: _substitute(str(v), context) for k, v in (step.get("with") or {}).items()}
        uses = step.get("uses", "")
        if uses.startswith(("actions/checkout@", "actions/setup-python@")):
            return 0
        if uses.startswith("actions/upload-artifact@"):
            shutil.copytree(self.checkout / with_["path"], self.store / with_["name"])
            return 0
        if uses.startswith("actions/download-artifact@"):
            for artifact in sorted(self.store.glob(with_["pattern"])):
                shutil.copytree(artifact, self.checkout / with_["path"] / artifact.name)
            return 0
        assert "run" in step, f"the local runner cannot run step {step}"
        command = _substitute(step["run"], context)
        self.commands.append(command)
        self.last = subprocess.run(
            ["bash", "-c", command], cwd=self.checkout, env=self.env, capture_output=True,
            text=True, check=False,
        )  # fmt: skip
        return self.last.returncode
