"""A report's statistics saved beside the run they were computed from (file I/O).

Layout, next to the results store's (:mod:`pytest_emrd.run._head`, ``_measured``)::

    <run>/aggregates/report.json    {"key": ..., "report": {...}}

Every table and figure of a report is a pure function of the episode files it reads, the
``--episode`` the map figure shows, and the code and libraries that compute it; fitting them
(Kaplan-Meier and Ebbinghaus through lifelines, the ANOVAs, the map alignment) costs more than
the rest of ``emrd report`` together. The first report of a run saves its :class:`Report`
here, and a later report of the very same episode files (another ``--format``, ``--out`` or
thresholds file) reads the statistics back instead of fitting them again.

The saved report is used only while its ``key`` matches: the SHA-256 over each episode's case
id and the SHA-256 of its episode file (as the run's heads were read for), ``--episode``, and
the :func:`~pytest_emrd.run.code_fingerprint` of the computing code and the installed versions
of its libraries (the ``nlp`` extra's too, or that it is absent). What depends on anything
else (overview and usage, prices, gate verdicts, the notes on what is missing) is never read
from here: :func:`~pytest_emrd.report.build_report` recomputes it. The file is scrubbed like
the episodes (the representative reasoning quotes model text). Saving is best effort: a run
directory that cannot be written to is reported from scratch every time.
"""

from __future__ import annotations

import functools
import hashlib
import importlib.metadata
import json
from collections.abc import Sequence
from pathlib import Path
from typing import Final

from pytest_emrd._atomic import write_bytes_atomic
from pytest_emrd._scrub import scrub_bytes
from pytest_emrd.errors import EmrdError
from pytest_emrd.report._model import Report
from pytest_emrd.run import StoredEpisode, code_fingerprint

#: The code that turns episode files into a report's tables and figures (fingerprinted).
AGGREGATES_CODE: Final = (
    "pytest_emrd.report",
    "pytest_emrd.metrics",
    "pytest_emrd.gate",
    "pytest_emrd.trajectory",
    "pytest_emrd.rooms",
    "pytest_emrd._serde",
)
#: The libraries it computes with (their versions enter the key).
AGGREGATES_LIBRARIES: Final = ("numpy", "scipy", "statsmodels", "lifelines", "pandas")
#: The ``nlp`` extra (representative reasoning): its versions, or that it is absent.
OPTIONAL_LIBRARIES: Final = ("sentence-transformers", "torch")


def aggregates_path(run_dir: Path) -> Path:
    """Where a run directory keeps the statistics of its last report."""
    return run_dir / "aggregates" / "report.json"


@functools.cache
def _code() -> str:
    digest = hashlib.sha256(code_fingerprint(AGGREGATES_CODE, AGGREGATES_LIBRARIES).encode())
    for dist in OPTIONAL_LIBRARIES:
        try:
            version = importlib.metadata.version(dist)
        except importlib.metadata.PackageNotFoundError:
            version = "absent"
        digest.update(f"\0{dist}=={version}".encode())
    return digest.hexdigest()


def aggregates_key(episodes: Sequence[StoredEpisode], *, episode: str | None) -> str | None:
    """The key a saved report's statistics are valid for (see the module); None when an
    episode is not read from a store file (a trajectory handed in), which is never saved."""
    digest = hashlib.sha256(f"{_code()}\0{episode}\0".encode())
    for stored in episodes:
        if not isinstance(stored.source, tuple):
            return None
        digest.update(f"{stored.head.spec.case_id}\0{stored.source[1]}\0".encode())
    return digest.hexdigest()


def read_aggregates(run_dir: Path, key: str) -> Report | None:
    """The report saved in ``run_dir`` under ``key``; None when missing, stale or unreadable
    (the caller computes it)."""
    try:
        document = json.loads(aggregates_path(run_dir).read_bytes())
        if document["key"] != key:
            return None
        return Report.from_dict(document["report"])
    except (OSError, ValueError, KeyError, TypeError, EmrdError):
        return None


def write_aggregates(run_dir: Path, key: str, report: Report) -> None:
    """Save ``report`` (its statistics) in ``run_dir`` under ``key``; nothing when the run
    directory cannot be written to."""
    blob = json.dumps({"key": key, "report": report.to_dict()}, separators=(",", ":")).encode()
    try:
        write_bytes_atomic(aggregates_path(run_dir), scrub_bytes(blob, literal_only=True))
    except OSError:
        return
