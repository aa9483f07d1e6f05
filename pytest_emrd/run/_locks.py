"""What the processes of one run directory share while they run, kept outside it (file I/O):
one file lock per episode and one for ``run.json``, and the per-session count of
unreachable episodes (:mod:`pytest_emrd.plugin._endpoint`), in a private folder of the OS
temporary directory named after the run directory. So a run directory holds only results,
and its locks are shared on one machine only, as pytest-xdist's workers are."""

from __future__ import annotations

import hashlib
import os
import tempfile
from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from filelock import FileLock


def scratch_dir(run_dir: Path) -> Path:
    """The folder of ``run_dir``'s locks and session state (not created here; create it
    with mode 0700): ``<OS temp dir>/pytest-emrd-<uid>/<16 hex digits of the SHA-256 of
    the resolved run_dir>``."""
    mine = f"pytest-emrd-{os.getuid()}" if hasattr(os, "getuid") else "pytest-emrd"  # Windows:
    key = hashlib.sha256(str(run_dir.resolve()).encode()).hexdigest()[:16]  # a per-user TEMP
    return Path(tempfile.gettempdir()) / mine / key


def run_lock(run_dir: Path, name: str, *, timeout: float = -1) -> FileLock:
    """The file lock ``name`` of ``run_dir`` (an episode's case id, or ``run.json``);
    filelock is imported here, so a resume that takes no lock never loads it."""
    from filelock import FileLock

    folder = scratch_dir(run_dir)
    folder.mkdir(mode=0o700, parents=True, exist_ok=True)
    return FileLock(folder / f"{name}.lock", timeout=timeout)
