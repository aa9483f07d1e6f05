"""Where an episode's cassette lives, and the commands that (re-)record episodes."""

from __future__ import annotations

import shlex
from collections import Counter
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Final

from pytest_emrd.cassette._file import SUFFIX
from pytest_emrd.rooms import SLUG_ROOMS
from pytest_emrd.trajectory import CONDITIONS, EpisodeSpec

#: The folder, inside the cassette folder, that holds lock files and unfinished writes. It
#: holds a ``.gitignore`` of ``*``, so ``git add cassettes`` never commits what is in it.
SCRATCH: Final = ".emrd-tmp"
#: The file name endings older releases wrote (``emrd cassettes upgrade`` converts them).
LEGACY_SUFFIXES: Final = (".yaml.gz", ".yaml.xz")

#: A model's registry default modality (``Registry.get(model).modality``), by model name.
ModalityOf = Callable[[str], str]


def cassette_path(root: Path, spec: EpisodeSpec, *, modality_of: ModalityOf | None = None) -> Path:
    """``<root>/<model>/<condition>/<variant>/<spawn>/ep<NN>.json.xz`` on the builtin world
    under the paper protocol; another backend and generated layouts get their own trees
    (``<root>/<backend>/...``, ``.../layouts-generated/...``) so a recording never answers a
    run of another world. An episode in another modality than its model's default
    (``modality_of``, the registry; without it ``spec.modality`` is the default) lives in a
    ``<variant>+<modality>`` folder. Layout and reasons: docs/cassettes.md.
    """
    base = root if spec.backend == "builtin" else root / spec.backend
    if spec.layouts != "paper":
        base = base / f"layouts-{spec.layouts}"
    variant = spec.variant
    if modality_of is not None and spec.modality != modality_of(spec.model):
        variant = f"{variant}+{spec.modality}"
    folder = base / spec.model / spec.condition / variant / spec.spawn
    return folder / f"ep{spec.episode:02d}{SUFFIX}"


def found_cassette(root: Path, spec: EpisodeSpec) -> Path:
    """The cassette of ``spec`` where no registry tells its model's default modality (a
    viewer of stored episodes): its ``<variant>+<modality>`` file when there is one (the
    modality is not the default), else the plain one."""
    own = cassette_path(root, spec, modality_of=lambda model: "")  # "": never the default
    return own if own.is_file() else cassette_path(root, spec)


def scratch_path(root: Path, path: Path, suffix: str) -> Path:
    """Where the lock file (``.lock``) or an unfinished write of the cassette ``path`` lives:
    the same relative path under :data:`SCRATCH` (created here, with its ``.gitignore``)."""
    scratch = root / SCRATCH
    target = scratch / path.relative_to(root)
    target.parent.mkdir(parents=True, exist_ok=True)
    ignore = scratch / ".gitignore"
    if not ignore.is_file():
        ignore.write_text("# pytest-emrd: cassette locks and unfinished writes\n*\n")
    return target.with_name(target.name + suffix)


@dataclass(frozen=True)
class Invocation:
    """What a printed ``pytest`` command must carry to work verbatim for this run."""

    paths: tuple[str, ...] = ("benchmarks",)
    """The test paths the user ran (``pytest benchmarks``, ``pytest suite/test_x.py``)."""
    models_file: Path | None = None
    """The user model registry (``--emrd-models``), needed to find a user model."""
    cassettes: Path | None = None
    """The cassette folder (``--emrd-cassettes``); ``None``: the default."""
    backend_options: tuple[str, ...] = ()
    """``--emrd-backend-option`` values as given (a THOR build path, a GPU)."""


def record_command(
    specs: EpisodeSpec | Sequence[EpisodeSpec],
    *,
    record_mode: str,
    cassettes: Path | None = None,
    invocation: Invocation | None = None,
) -> str:
    """The exact ``pytest`` command that records (``once``) or re-records (``all``) one
    episode, or every episode of ``specs`` in one run (``once`` records only what is missing),
    working verbatim for this ``invocation`` (``cassettes`` overrides its folder)."""
    one = isinstance(specs, EpisodeSpec)
    group = [specs] if one else list(specs)
    how = invocation or Invocation()
    first = group[0]
    args = ["pytest", *how.paths]
    args += [f"--emrd-model={m}" for m in sorted({s.model for s in group})]
    args += [f"--emrd-condition={c}" for c in _ordered(group, "condition", CONDITIONS)]
    args += [f"--emrd-spawn={r}" for r in _ordered(group, "spawn", tuple(SLUG_ROOMS))]
    args.append(f"--emrd-episodes={max(s.episode for s in group) + 1}")
    for name, default in (("variant", "default"), ("backend", "builtin"), ("layouts", "paper")):
        if getattr(first, name) != default:
            args.append(f"--emrd-{name}={getattr(first, name)}")
    args += [f"--emrd-backend-option={o}" for o in how.backend_options]
    if len({s.modality for s in group}) == 1:
        args.append(f"--emrd-modality={first.modality}")
    if how.models_file is not None:
        args.append(f"--emrd-models={how.models_file}")
    folder = cassettes if cassettes is not None else how.cassettes
    if folder is not None:
        args.append(f"--emrd-cassettes={folder}")
    selection = f"test_episode and {first.case_id}" if one else "test_episode"
    args += [f"--emrd-record-mode={record_mode}", "-k", selection]
    return shlex.join(args)


def _ordered(group: Sequence[EpisodeSpec], field: str, order: Sequence[str]) -> list[str]:
    present = {getattr(s, field) for s in group}
    return [x for x in order if x in present] + sorted(present - set(order))


def missing_cassettes(
    specs: Sequence[EpisodeSpec], root: Path, *, modality_of: ModalityOf | None = None
) -> list[EpisodeSpec]:
    """The episodes of ``specs`` whose cassette file does not exist under ``root``."""
    return [s for s in specs if not cassette_path(root, s, modality_of=modality_of).is_file()]


def missing_summary(
    missing: Sequence[EpisodeSpec],
    *,
    total: int,
    root: Path,
    invocation: Invocation,
    modality_of: ModalityOf | None = None,
) -> str:
    """The one message for a replay-only run with missing cassettes: how many, for which
    models, and one command that records them all."""
    per_model = Counter(spec.model for spec in missing)
    models = ", ".join(f"{m} ({n})" for m, n in sorted(per_model.items()))
    command = record_command(missing, record_mode="once", cassettes=root, invocation=invocation)
    old = sum(_has_legacy_twin(cassette_path(root, s, modality_of=modality_of)) for s in missing)
    convert = (
        f" {old} of them have a cassette an older pytest-emrd wrote: convert those first with: "
        f"emrd cassettes upgrade {root}."
        if old
        else ""
    )
    return (
        f"{len(missing)} of {total} episode(s) have no cassette under {root} and record mode "
        f"'none' replays only; missing for: {models}.{convert} Record them all "
        f"with: {command}"
    )


def _has_legacy_twin(path: Path) -> bool:
    stem = path.name[: -len(SUFFIX)]
    return any(path.with_name(stem + suffix).is_file() for suffix in LEGACY_SUFFIXES)
