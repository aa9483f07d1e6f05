"""Fingerprints of code: what a result saved beside a run's episodes was computed with."""

from __future__ import annotations

import hashlib
import importlib.metadata
import importlib.util
from collections.abc import Iterable
from pathlib import Path


def code_fingerprint(modules: Iterable[str], distributions: Iterable[str] = ()) -> str:
    """SHA-256 over the source of ``modules`` (every ``.py`` file of a package) and the
    installed versions of ``distributions``: changes whenever that code may compute
    differently."""
    digest = hashlib.sha256()
    for name in modules:
        spec = importlib.util.find_spec(name)
        if spec is None or spec.origin is None:
            raise ModuleNotFoundError(f"module={name!r} cannot be found to fingerprint")
        roots = spec.submodule_search_locations
        files = sorted(p for r in roots for p in Path(r).rglob("*.py")) if roots else []
        for path in files or [Path(spec.origin)]:
            digest.update(f"{name}:{path.name}\0".encode())
            digest.update(path.read_bytes())
    for dist in distributions:
        digest.update(f"{dist}=={importlib.metadata.version(dist)}\0".encode())
    return digest.hexdigest()
