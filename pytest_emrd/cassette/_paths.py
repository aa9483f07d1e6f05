"""Where an episode's cassette lives, the commands that (re-)record episodes, and what a
failed replay says, each cause with the command that fixes it: drift (the first differing
field of a request the cassette does not hold), a modality mismatch, and an unreadable
recorded response (one the client asked for again: a retry)."""

from __future__ import annotations

import shlex
from collections import Counter
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from itertools import zip_longest
from pathlib import Path
from typing import Any, Final

from pytest_emrd._scrub import scrub
from pytest_emrd.agent import VISIBLE_HEADING
from pytest_emrd.cassette._file import SUFFIX
from pytest_emrd.cassette._redact import Redacted
from pytest_emrd.rooms import SLUG_ROOMS
from pytest_emrd.trajectory import CONDITIONS, EpisodeSpec

#: The folder, inside the cassette folder, that holds lock files and unfinished writes. It
#: holds a ``.gitignore`` of ``*``, so ``git add cassettes`` never commits what is in it.
SCRATCH: Final = ".emrd-tmp"
#: The file name endings older releases wrote, all under protocols before this release's.
LEGACY_SUFFIXES: Final = (".yaml.gz", ".yaml.xz")
_PREVIEW: Final = 80
_CONTEXT: Final = 40
_BODY_EXCERPT: Final = 160
_MISSING: Final = "<absent>"
_ABSENT: Final = object()

#: A model's registry default modality (``Registry.get(model).modality``), by model name.
ModalityOf = Callable[[str], str]


def cassette_path(root: Path, spec: EpisodeSpec, *, modality_of: ModalityOf | None = None) -> Path:
    """``<root>/<model>/<condition>/<variant>/<spawn>/ep<NN>.json.xz`` on the builtin world under
    the paper protocol; another backend or layouts get their own tree (``<root>/<backend>/``,
    ``layouts-generated/``), another modality than the model's default (``modality_of``; else
    ``spec.modality``) a ``<variant>+<modality>`` folder (docs/cassettes.md).

    :param root: The cassette folder.
    :param spec: The episode.
    :param modality_of: Model name -> its default modality; None to take ``spec.modality``.
    :returns: The cassette's path (it need not exist).
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
    """The cassette of ``spec`` where no registry tells the default modality (a viewer): its
    ``<variant>+<modality>`` file when there is one, else the plain one.

    :param root: The cassette folder.
    :param spec: The episode.
    :returns: The path of the modality file if present, else the plain path.
    """
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
    episodes: int | None = None,
) -> str:
    """The exact ``pytest`` command that records (``once``) or re-records (``all``) one
    episode, or every episode of ``specs`` in one run (``once`` records only what is missing),
    working verbatim for this ``invocation`` (``cassettes`` overrides its folder; ``episodes``
    the run's ``--emrd-episodes``, else the highest episode of ``specs`` + 1).

    :param specs: One episode or several.
    :param record_mode: ``once`` or ``all``.
    :param cassettes: The cassette folder, if not the invocation's.
    :param invocation: The pytest invocation to repeat; None for a plain one.
    :param episodes: The ``--emrd-episodes`` value to pass.
    :returns: The shell command line.
    """
    one = isinstance(specs, EpisodeSpec)
    group = [specs] if one else list(specs)
    how = invocation or Invocation()
    first = group[0]
    args = ["pytest", *how.paths]
    args += [f"--emrd-model={m}" for m in sorted({s.model for s in group})]
    args += [f"--emrd-condition={c}" for c in _ordered(group, "condition", CONDITIONS)]
    args += [f"--emrd-spawn={r}" for r in _ordered(group, "spawn", tuple(SLUG_ROOMS))]
    args.append(f"--emrd-episodes={episodes or max(s.episode for s in group) + 1}")
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


def missing_summary(
    specs: Sequence[EpisodeSpec],
    *,
    total: int,
    root: Path,
    invocation: Invocation,
    modality_of: ModalityOf | None = None,
    episodes: int | None = None,
) -> str | None:
    """The one message for a replay-only run where episodes of ``specs`` have no cassette
    under ``root``: how many, for which models, and one command that records them all; when
    the run asks for more ``episodes`` per spawn room than every missing one's folder holds,
    how many are recorded and the setting to change.

    :param specs: The episodes without a cassette.
    :param total: Episodes in the run, for "N of M".
    :param root: The cassette folder.
    :param invocation: How pytest was started, for the record command.
    :param modality_of: Default modality per model, as for :func:`cassette_path`.
    :param episodes: Episodes per spawn room the run asks for; None when not set.
    :returns: The message, or None when nothing is missing.
    """
    paths = {s: cassette_path(root, s, modality_of=modality_of) for s in specs}
    missing = [s for s in specs if not paths[s].is_file()]
    if not missing:
        return None
    per_model = Counter(spec.model for spec in missing)
    models = ", ".join(f"{m} ({n})" for m, n in sorted(per_model.items()))
    command = record_command(
        missing, record_mode="once", cassettes=root, invocation=invocation, episodes=episodes
    )
    recorded = {_recorded(paths[s].parent) for s in missing}
    fewer = ""
    fewest = min(recorded)
    if episodes and fewest and all(s.episode >= _recorded(paths[s].parent) for s in missing):
        fewer = (
            f" This run asks for {episodes} episode(s) per spawn room (--emrd-episodes, "
            f"EMRD_EPISODES in the CI example) and the cassettes hold {fewest}"
            f"{'' if len(recorded) == 1 else ' or more'}: set --emrd-episodes={fewest} to "
            "replay what is recorded, or record the rest."
        )
    old = sum(_has_legacy_twin(cassette_path(root, s, modality_of=modality_of)) for s in missing)
    convert = ""
    if old:
        convert = (
            f" {old} of them have a cassette an older pytest-emrd wrote (*.yaml.gz, *.yaml.xz), "
            "under an earlier protocol: those cannot replay with this release, and the "
            "command below records them again (delete the old files afterwards)."
        )
    return (
        f"{len(missing)} of {total} episode(s) have no cassette under {root} and record mode "
        f"'none' replays only; missing for: {models}.{fewer}{convert} Record them all "
        f"with: {command}"
    )


def _recorded(folder: Path) -> int:
    """How many episodes ``folder`` holds from ``ep00`` on without a gap."""
    return next(n for n in range(1000) if not (folder / f"ep{n:02d}{SUFFIX}").is_file())


def _has_legacy_twin(path: Path) -> bool:
    stem = path.name[: -len(SUFFIX)]
    return any(path.with_name(stem + suffix).is_file() for suffix in LEGACY_SUFFIXES)


def _preview(value: Any) -> str:
    text = repr(value)
    return text if len(text) <= _PREVIEW else text[: _PREVIEW - 3] + "..."


def first_difference(new: Any, recorded: Any, where: str = "body") -> tuple[str, Any, Any] | None:
    """``(path, new value, recorded value)`` of the first difference, depth first, or None.

    Dict keys are visited in sorted order (the canonical order), list items by index; a key
    or item present on one side only is reported with ``<absent>`` on the other.
    """
    if isinstance(new, dict) and isinstance(recorded, dict):
        keys = sorted(set(new) | set(recorded))
        pairs = [(f"{where}.{k}", new.get(k, _ABSENT), recorded.get(k, _ABSENT)) for k in keys]
    elif isinstance(new, list) and isinstance(recorded, list):
        items = enumerate(zip_longest(new, recorded, fillvalue=_ABSENT))
        pairs = [(f"{where}[{i}]", a, b) for i, (a, b) in items]
    else:
        return None if new == recorded and type(new) is type(recorded) else (where, new, recorded)
    for path, a, b in pairs:
        if a is _ABSENT or b is _ABSENT:
            return path, _MISSING if a is _ABSENT else a, _MISSING if b is _ABSENT else b
        if found := first_difference(a, b, path):
            return found
    return None


def text_context(now: str, then: str, width: int = _CONTEXT) -> str:
    """Where two texts first differ, with ``width`` characters of context on each side."""
    pairs = enumerate(zip(now, then, strict=False))
    at = next((i for i, (a, b) in pairs if a != b), min(len(now), len(then)))
    start = max(0, at - width)
    lead = "..." if start else ""

    def window(text: str) -> str:
        tail = "..." if len(text) > at + width else ""
        return repr(text[start : at + width]) + tail

    return (
        f"at character {at} (of {len(now)} now, {len(then)} recorded): "
        f"now {lead}{window(now)}, recorded {lead}{window(then)}"
    )


def request_modality(redacted: Redacted) -> str | None:
    """The modality a recorded request was made in: frames and a symbolic list (``both``),
    frames only (``vision``), the list only (``text``); ``None`` when the body is not JSON."""
    if not redacted.parsed:
        return None
    listed = VISIBLE_HEADING in redacted.body.decode(errors="replace")
    if redacted.images:
        return "both" if listed else "vision"
    return "text"


def drift_message(
    *,
    cassette: str,
    request_index: int,
    new_tree: Any,
    recorded_tree: Any | None,
    recorded: int,
    command: str = "",
) -> str:
    """The failure text of a request that matches nothing in the cassette."""
    head = (
        f"environment or prompt drift: request {request_index + 1} of the episode matches "
        f"nothing in cassette={cassette!r}"
    )
    fix = f" If the change is intended, re-record it: {command}" if command else ""
    if new_tree is None:
        return f"{head}; its body is not JSON, and a body that cannot be parsed never matches."
    if recorded_tree is None:
        return (
            f"{head}; the cassette holds only {recorded} request(s), so the episode now makes "
            f"more requests than when it was recorded (the world or the agent behaves "
            f"differently).{fix}"
        )
    found = first_difference(new_tree, recorded_tree)
    if found is None:
        return (
            f"{head}; the body equals recorded request {request_index + 1}, "
            f"which was already played.{fix}"
        )
    where, now, then = found
    if isinstance(now, str) and isinstance(then, str):
        detail = text_context(now, then)
    else:
        detail = f"now {_preview(now)}, recorded {_preview(then)}"
    return f"{head}; first differing field {where} {detail}.{fix}"


def modality_message(
    *, cassette: Path, recorded: str, asked: str, home: Path, record: str, rerecord: str
) -> str:
    """The failure text of a replay in another modality than the recording. ``home`` is where an
    episode in the ``recorded`` modality keeps its cassette: when it is free the fix moves the
    file there, then records the ``asked`` episode with ``record``; when it holds one, this
    file is a stray copy that ``rerecord`` replaces. No fix overwrites a ``recorded`` cassette."""
    head = (
        f"modality mismatch: cassette={str(cassette)!r} was recorded in modality {recorded!r} "
        f"and this run shows the model {asked!r}."
    )
    if home == cassette:  # no registry to tell the modalities' paths apart
        return (
            f"{head} Replay it with --emrd-modality={recorded}, or replace it by the {asked!r} "
            f"episode (the {recorded!r} recording is lost): {rerecord}"
        )
    if home.is_file():
        return (
            f"{head} The {recorded!r} episode has its own cassette, {home} (replay it with "
            f"--emrd-modality={recorded}); re-record this one in {asked!r}: {rerecord}"
        )
    folder = shlex.join(["mkdir", "-p", str(home.parent)])
    move = f"{folder} && {shlex.join(['mv', str(cassette), str(home)])}"
    return (
        f"{head} A {recorded!r} episode belongs at {home}: move it there ({move}; it then "
        f"replays with --emrd-modality={recorded}), then record the {asked!r} episode: {record}"
    )


def unreadable_message(
    *, cassette: str, response_index: int, response: dict[str, Any], command: str
) -> str:
    """The failure text of a recorded response the client could not read."""
    status = response.get("status", {}).get("code", "?")
    body = response.get("body", {}).get("string", b"")
    text = body.decode(errors="replace") if isinstance(body, bytes) else str(body)
    excerpt = " ".join(text.split())[:_BODY_EXCERPT]
    return (
        f"unreadable recorded response: response {response_index + 1} of cassette="
        f"{cassette!r} (HTTP {status}) was replayed and the client could not read it as a "
        f"reply (it asked for the same request again); the body starts {scrub(excerpt)!r}. "
        f"The file is damaged or was recorded from another endpoint; re-record it: {command}"
    )
