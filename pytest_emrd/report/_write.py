"""Writing a report's files into a folder (file I/O only)."""

from __future__ import annotations

import os
from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import Final

from pytest_emrd._atomic import write_bytes_atomic
from pytest_emrd._scrub import scrub, scrub_bytes
from pytest_emrd.report._model import Report
from pytest_emrd.report._render import FORMATS, render_files

#: Files scrubbed before they are written (figures are pixels).
TEXT_SUFFIXES: Final = frozenset({".md", ".html", ".json", ".txt", ".csv"})


def write_files(files: Mapping[str, bytes], out_dir: Path) -> list[Path]:
    """Write each ``name -> content`` into ``out_dir`` (created if needed), atomically; text
    files are scrubbed of secrets first (a report quotes errored episodes' causes)."""
    written = []
    for name, content in files.items():
        path = out_dir / name
        text = path.suffix in TEXT_SUFFIXES
        write_bytes_atomic(path, scrub_bytes(content) if text else content)
        written.append(path)
    return written


def append_step_summary(text: str) -> bool:
    """Append ``text`` (Markdown, scrubbed of secrets) to ``$GITHUB_STEP_SUMMARY``; ``False``
    when it is not set."""
    target = os.environ.get("GITHUB_STEP_SUMMARY")
    if not target:
        return False
    text = scrub(text)
    with open(target, "a", encoding="utf-8") as summary:
        summary.write(text if text.endswith("\n") else text + "\n")
    return True


def write_report(
    report: Report, out_dir: Path, formats: Iterable[str] = FORMATS, *, processes: int = 1
) -> list[Path]:
    """Render ``report`` in ``formats`` (figures drawn in ``processes`` processes) and write it
    into ``out_dir``; the paths written."""
    return write_files(render_files(report, formats, processes=processes), out_dir)
