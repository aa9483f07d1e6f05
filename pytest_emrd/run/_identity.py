"""Which run a run directory belongs to (``<run>/run.json``: its grid and shard, so ``emrd
gate`` refuses an incomplete or duplicated set of shards), and what its processes share:
one file lock per episode and one for ``run.json``, and the per-session count of unreachable
episodes (:mod:`pytest_emrd.plugin._endpoint`), in a private folder of the OS temporary
directory (:func:`scratch_dir`), so a run directory holds only results. Run directories
written before ``run.json`` existed are taken as they are."""

from __future__ import annotations

import hashlib
import json
import os
import tempfile
from collections import defaultdict
from collections.abc import Sequence
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, Final

from pytest_emrd import __version__
from pytest_emrd._files import write_bytes_atomic
from pytest_emrd.errors import ConfigError
from pytest_emrd.run._settings import RunSettings

if TYPE_CHECKING:
    from filelock import FileLock

RUN_FILE: Final = "run.json"
IDENTITY_SCHEMA: Final = 1
_GRID_LISTS: Final = ("models", "conditions", "spawns")


@dataclass(frozen=True)
class RunIdentity:
    """What one run directory holds (the file format of ``run.json``)."""

    grid: dict[str, Any]
    """The episode grid asked for: models, conditions, spawns, episodes, variant, backend,
    modality (``None``: each model's registry default) and protocol."""
    shard: tuple[int, int] | None
    """``(K, N)``: the K-th of N slices of the grid; ``None`` for the whole grid."""
    schema_version: int = IDENTITY_SCHEMA

    @property
    def grid_id(self) -> str:
        """12 hex digits identifying the grid: shards of one CI matrix share it."""
        text = json.dumps(self.grid, sort_keys=True, separators=(",", ":"))
        return hashlib.sha256(text.encode()).hexdigest()[:12]

    def describe(self) -> str:
        """The grid in words for messages (``models gpt, 3 conditions, 4 spawns x 20``)."""
        g = self.grid
        return (
            f"grid {self.grid_id}: models {', '.join(g['models'])}; "
            f"{len(g['conditions'])} condition(s) x {len(g['spawns'])} spawn(s) x "
            f"{g['episodes']} episode(s)"
        )

    def to_dict(self) -> dict[str, Any]:
        return {**asdict(self), "grid_id": self.grid_id, "shard": self.shard and list(self.shard)}

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> RunIdentity:
        shard = data.get("shard")
        return cls(
            grid=dict(data["grid"]),
            shard=(int(shard[0]), int(shard[1])) if shard else None,
            schema_version=int(data.get("schema_version", IDENTITY_SCHEMA)),
        )

    @classmethod
    def of(cls, settings: RunSettings, protocol: str) -> RunIdentity:
        grid: dict[str, Any] = {k: sorted(getattr(settings, k)) for k in _GRID_LISTS}
        grid |= {k: getattr(settings, k) for k in ("episodes", "variant", "backend", "modality")}
        return cls(grid={**grid, "protocol": protocol}, shard=settings.shard)


def read_identity(run_dir: Path) -> RunIdentity | None:
    """The identity recorded in ``run_dir``, or ``None`` when it has none.

    :param run_dir: A run directory.
    :returns: Its :class:`RunIdentity`, or None.
    """
    path = run_dir / RUN_FILE
    try:
        identity = RunIdentity.from_dict(json.loads(path.read_bytes()))
    except FileNotFoundError:
        return None
    except (OSError, ValueError, KeyError, TypeError, IndexError) as exc:
        raise ConfigError(
            f"{path} cannot be read ({type(exc).__name__}); it records the run's shard. "
            "Delete it only if you know which shard the directory holds."
        ) from None
    if identity.schema_version != IDENTITY_SCHEMA:
        raise ConfigError(
            f"{path} has schema_version={identity.schema_version}, but pytest-emrd "
            f"{__version__} reads schema_version {IDENTITY_SCHEMA}; read this run directory "
            "with the release that wrote it, or give this run another --emrd-results."
        )
    return identity


def check_resume(run_dir: Path, shard: tuple[int, int] | None) -> None:
    """Refuse to write shard ``shard`` into a run directory that holds another shard.

    :param run_dir: The run directory resumed.
    :param shard: ``(k, n)``, or None for an unsharded run.
    :raises ConfigError: When the directory holds another shard.
    """
    found = read_identity(run_dir)
    if found is not None and found.shard != shard:
        wanted = f"{shard[0]}/{shard[1]}" if shard else "the whole grid"
        held = f"{found.shard[0]}/{found.shard[1]}" if found.shard else "whole grid"
        raise ConfigError(
            f"--emrd-results={run_dir} holds shard {held} of {found.describe()}; "
            f"this run is {wanted}. Give each shard its own run directory."
        )


def write_identity(run_dir: Path, identity: RunIdentity) -> None:
    """Record ``identity`` in ``run_dir`` under its lock, refusing another shard's directory.

    :param run_dir: The run directory.
    :param identity: The grid and shard to record.
    :raises ConfigError: When the directory holds another shard.
    """
    path = run_dir / RUN_FILE
    blob = json.dumps(identity.to_dict(), sort_keys=True, indent=1).encode()
    with run_lock(run_dir, RUN_FILE):
        check_resume(run_dir, identity.shard)
        if not path.is_file() or path.read_bytes() != blob:
            write_bytes_atomic(path, blob)


def check_shard_set(run_dirs: Sequence[Path], *, allow_partial: bool = False) -> list[str]:
    """The problems of ``run_dirs`` as shard sets (missing or repeated shards and their
    directories; empty when complete), a :class:`ConfigError` unless ``allow_partial``.

    :param run_dirs: The directories of one sharded run.
    :param allow_partial: Return the problems instead of raising.
    :returns: The problems, one line each; empty when the set is complete.
    """
    problems: list[str] = []
    seen: dict[Path, Path] = {}
    groups: dict[str, list[tuple[Path, RunIdentity]]] = defaultdict(list)
    for run_dir in run_dirs:
        real = run_dir.resolve()
        if real in seen:
            problems.append(f"{run_dir} is given twice (also as {seen[real]})")
            continue
        seen[real] = run_dir
        identity = read_identity(run_dir)
        if identity is not None:
            groups[identity.grid_id].append((run_dir, identity))
    for members in groups.values():
        problems += _group_problems(members)
    if problems and not allow_partial:
        raise ConfigError(
            "the run directories are not one complete set of shards: "
            + "; ".join(problems)
            + ". Pass every shard's run directory once, or --allow-partial to gate on what "
            "is there."
        )
    return problems


def _group_problems(members: list[tuple[Path, RunIdentity]]) -> list[str]:
    described = members[0][1].describe()
    by_shard: dict[tuple[int, int] | None, list[Path]] = defaultdict(list)
    for run_dir, identity in members:
        by_shard[identity.shard].append(run_dir)
    problems = [
        f"{'the whole grid' if shard is None else f'shard {shard[0]}/{shard[1]}'} of "
        f"{described} is in {len(dirs)} directories ({', '.join(map(str, dirs))})"
        for shard, dirs in by_shard.items()
        if len(dirs) > 1
    ]
    sizes = sorted({shard[1] for shard in by_shard if shard is not None})
    if None in by_shard and sizes:
        problems.append(f"{described} is given whole and as shards")
    if len(sizes) > 1:
        problems.append(f"{described} mixes shard counts {sizes}")
    for n in sizes:
        present = {shard[0] for shard in by_shard if shard is not None and shard[1] == n}
        missing = [f"{k}/{n}" for k in range(1, n + 1) if k not in present]
        if missing:
            have = ", ".join(f"{k}/{n} ({by_shard[(k, n)][0]})" for k in sorted(present))
            problems.append(
                f"{described} has {len(present)} of {n} shards ({have}); missing "
                f"{', '.join(missing)}"
            )
    return problems


def scratch_dir(run_dir: Path) -> Path:
    """The folder of ``run_dir``'s locks and session state, not created here (create it with
    mode 0700): ``<OS temp dir>/pytest-emrd-<uid>/<SHA-256 of the resolved run_dir, 16 hex>``.

    :param run_dir: A run directory.
    :returns: The scratch folder's path.
    """
    mine = f"pytest-emrd-{os.getuid()}" if hasattr(os, "getuid") else "pytest-emrd"  # Windows:
    key = hashlib.sha256(str(run_dir.resolve()).encode()).hexdigest()[:16]  # a per-user TEMP
    return Path(tempfile.gettempdir()) / mine / key


def run_lock(run_dir: Path, name: str, *, timeout: float = -1) -> FileLock:
    """The file lock ``name`` of ``run_dir`` (imported here: a resume never loads filelock)."""
    from filelock import FileLock

    folder = scratch_dir(run_dir)
    folder.mkdir(mode=0o700, parents=True, exist_ok=True)
    return FileLock(folder / f"{name}.lock", timeout=timeout)
