"""Atomic file writes: a reader sees the old file or the new one, never half of either."""

from __future__ import annotations

import os
import tempfile
from pathlib import Path


def write_bytes_atomic(path: Path, data: bytes, *, temp: Path | None = None) -> None:
    """Write ``data`` to ``path`` via ``<temp>.<random>.tmp`` (``temp`` on the same file
    system; default ``.<name>`` beside ``path``) and a rename, with the usual permissions
    (``0o666`` minus the umask), not ``mkstemp``'s 0600."""
    path.parent.mkdir(parents=True, exist_ok=True)
    temp = temp or path.with_name(f".{path.name}")
    fd, tmp = tempfile.mkstemp(prefix=f"{temp.name}.", suffix=".tmp", dir=temp.parent)
    try:
        with os.fdopen(fd, "wb") as handle:
            handle.write(data)
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o666 & ~umask)
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
