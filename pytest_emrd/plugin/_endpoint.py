"""Fail fast on a dead endpoint: a model whose last :data:`DEAD_AFTER` computed episodes in a
row ended on a connection failure or a timeout is not called again in this session. Its
remaining episodes are skipped with one reason, and the end of the run names the endpoint
and the command that resumes the run. The count is shared by the session's xdist workers
(``endpoints/<model>.json`` in :func:`~pytest_emrd.run.scratch_dir`, under a file lock)."""

from __future__ import annotations

import json
import re
import shlex
from collections.abc import Sequence
from pathlib import Path
from typing import Any, Final

from pytest_emrd._files import write_bytes_atomic
from pytest_emrd._scrub import scrub
from pytest_emrd.run import scratch_dir

DEAD_AFTER: Final = 3
"""Consecutive unreachable episodes of one model that stop its remaining episodes."""
#: Transport failures that say nothing answered (as opposed to an answer we did not like).
_UNREACHABLE: Final = re.compile(
    r"Connect(?:Error|Timeout)|(?:Read|Write|Pool)Timeout|timed out|RemoteProtocolError|"
    r"ReadError|Connection refused|Name or service not known"
)


def unreachable(status: str, error: str | None) -> bool:
    """Whether an episode ended because its endpoint could not be reached or timed out."""
    return status == "errored" and error is not None and bool(_UNREACHABLE.search(error))


class EndpointWatch:
    """Per model, the consecutive unreachable episodes of this session (shared by workers)."""

    def __init__(self, run_dir: Path, session: str, args: Sequence[str]) -> None:
        self.folder = scratch_dir(run_dir) / "endpoints"
        self.run_dir, self.session, self.args = run_dir, session, tuple(args)

    def _read(self, model: str) -> dict[str, Any]:
        path = self.folder / f"{model}.json"
        try:
            data = json.loads(path.read_text(encoding="utf-8"))
        except (OSError, ValueError):
            return {}
        return data if isinstance(data, dict) and data.get("session") == self.session else {}

    def record(self, model: str, endpoint: str, status: str, error: str | None) -> None:
        """Count one computed episode of ``model`` (a stopped model's count is final)."""
        from filelock import FileLock

        self.folder.mkdir(mode=0o700, parents=True, exist_ok=True)
        with FileLock(str(self.folder / f"{model}.lock")):
            data = self._read(model) or {"session": self.session, "consecutive": 0}
            if data.get("stopped"):
                return
            down = unreachable(status, error)
            data["consecutive"] = data["consecutive"] + 1 if down else 0
            if down and data["consecutive"] >= DEAD_AFTER:
                data.update(stopped=True, endpoint=endpoint, error=error)
            write_bytes_atomic(self.folder / f"{model}.json", json.dumps(data).encode())

    def resume_command(self) -> str:
        """This session's ``pytest`` command, resuming its run directory."""
        args, given = [], iter(self.args)
        for arg in given:  # without the run directory given (it is added back)
            if arg == "--emrd-results":
                next(given, None)  # its value
            elif not arg.startswith("--emrd-results="):
                args.append(arg)
        return shlex.join(["pytest", *args, f"--emrd-results={self.run_dir}"])

    def stop_reason(self, model: str) -> str | None:
        """The one message of ``model``'s stop in this session (what happened, the endpoint,
        how to resume), or ``None`` while it is called."""
        data = self._read(model)
        if not data.get("stopped"):
            return None
        return scrub(
            f"pytest-emrd: stopped calling model {model!r}: {data['consecutive']} episodes in a "
            f"row could not reach {data['endpoint']} (last: {data['error']}). Its remaining "
            "episodes were not attempted; every recorded episode is kept. When the endpoint "
            f"answers again, resume with: {self.resume_command()}"
        )

    def pytest_terminal_summary(self, terminalreporter: Any) -> None:
        for path in sorted(self.folder.glob("*.json")):  # none before an episode ran
            reason = self.stop_reason(path.stem)
            if reason is not None:
                terminalreporter.write_line(reason, red=True)
