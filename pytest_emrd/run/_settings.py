"""The run's settings: every ``--emrd-*`` option, its ini twin and default, resolved once, in
:func:`resolve_settings` (command line > ini file > default); :data:`OPTIONS` is what the
plugin registers, so ``pytest --help``, the ini keys and the resolution cannot drift apart."""

from __future__ import annotations

import json
import os
import warnings
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Final

from pytest_emrd._files import check_slug
from pytest_emrd.errors import ConfigError, check_choice, check_positive_int
from pytest_emrd.rooms import ROOM_SLUGS
from pytest_emrd.trajectory import (
    CONDITIONS,
    LAYOUTS,
    MATCHING_MODES,
    MODALITIES,
    RECORD_MODES,
    VARIANTS,
)

BACKENDS: Final[tuple[str, ...]] = ("builtin", "ai2thor")
SPAWNS: Final[tuple[str, ...]] = tuple(ROOM_SLUGS.values())
MAX_EPISODES: Final = 1000
"""Cap on ``--emrd-episodes`` (episodes per spawn room; the paper's setting is 20)."""
MAX_CONCURRENCY: Final = 32
"""Cap on ``--emrd-concurrency`` (threads per process, each holding an episode's frames)."""
_NOT_CI: Final = frozenset({"", "0", "false", "no", "off"})
#: What ``pytest benchmarks`` covers without ``--emrd-model``: the reference agents whose
#: cassettes are committed, each under its recorded conditions (``mimic``: baseline only).
DEFAULT_CELLS: Final = (("scout", CONDITIONS), ("mimic", ("baseline",)))
LENIENT_BACKENDS: Final[frozenset[str]] = frozenset({"ai2thor"})
"""Backends whose frames are not bit-stable: their cassettes replay with lenient matching."""


class MatchingWarning(UserWarning):
    """Strict matching was asked for on a backend whose frames are not bit-stable."""


@dataclass(frozen=True)
class Option:
    """One ``--emrd-<name>`` option and its ini key ``emrd_<name>``."""

    name: str
    help: str
    choices: tuple[str, ...] | None = None
    repeatable: bool = False
    metavar: str | None = None

    @property
    def flag(self) -> str:
        return "--emrd-" + self.name.replace("_", "-")

    @property
    def ini(self) -> str:
        return "emrd_" + self.name

    def argparse_kwargs(self, dest: str) -> dict[str, Any]:
        """``add_argument``/``addoption`` keyword arguments (pytest's parser and ``emrd``)."""
        kwargs: dict[str, Any] = {"dest": dest, "default": None, "help": self.help}
        if self.repeatable:
            kwargs["action"] = "append"
        elif self.choices:
            kwargs["choices"] = self.choices
        if self.metavar:
            kwargs["metavar"] = self.metavar
        return kwargs


OPTIONS: Final[tuple[Option, ...]] = (
    Option(
        "model",
        "model to benchmark, repeatable (default: the built-in reference agents "
        "scout, under every condition, and mimic, under baseline); any name of the model "
        "registry",
        repeatable=True,
        metavar="NAME",
    ),
    Option(
        "condition",
        "environmental condition, repeatable (default: all three)",
        CONDITIONS,
        repeatable=True,
    ),
    Option("spawn", "spawn room, repeatable (default: all four)", SPAWNS, repeatable=True),
    Option(
        "episodes",
        "episodes per spawn room (default: 20, the paper's setting; at most 1000)",
        metavar="N",
    ),
    Option("variant", "prompt variant (default: default)", VARIANTS),
    Option(
        "layouts",
        "offices the episodes run in: paper is the paper's protocol, one fixed "
        "office for every episode; generated gives every spawn x episode its own "
        "procedurally generated office, a generalisation study gated and reported as its "
        "own cells (default: paper)",
        LAYOUTS,
    ),
    Option("backend", "world backend (default: builtin)", BACKENDS),
    Option(
        "backend_option",
        "simulator option KEY=VALUE for the backend, repeatable (e.g. "
        "local_executable_path=/path/to/thor, gpu_device=1, start_timeout=300); VALUE is "
        "read as JSON when it parses (1, 2.5, true) and kept as text otherwise",
        repeatable=True,
        metavar="KEY=VALUE",
    ),
    Option("modality", "what the model is shown (default: the model's registry entry)", MODALITIES),
    Option(
        "record_mode",
        "cassette record mode: none replays only with the network blocked, "
        "once records missing cassettes, new_episodes also re-records a drifted episode "
        "whole, all re-records (default: once, or none when the CI environment variable is set)",
        RECORD_MODES,
    ),
    Option(
        "matching",
        "request matching: strict keys frames by pixel digest, lenient only "
        "warns on differing frames (default: lenient on ai2thor, strict otherwise)",
        MATCHING_MODES,
    ),
    Option(
        "results",
        "run directory to write or resume (default: a fresh directory under <rootdir>/.emrd/runs)",
        metavar="DIR",
    ),
    Option(
        "thresholds",
        "release gates file (default: <rootdir>/thresholds.yaml if it exists; "
        "without one the run has episodes and no gates)",
        metavar="FILE",
    ),
    Option(
        "models", "user model registry YAML extending/overriding the shipped one", metavar="FILE"
    ),
    Option("cassettes", "cassette folder (default: <rootdir>/cassettes)", metavar="DIR"),
    Option(
        "shard",
        "run the K-th of N deterministic slices of the episodes (gates are then "
        "evaluated with `emrd gate RUN_DIR...`)",
        metavar="K/N",
    ),
    Option(
        "concurrency",
        "live episodes each process records at once, in threads, against "
        "a remote model (default: 1, at most 32); replays are not affected",
        metavar="N",
    ),
    Option(
        "preflight",
        "check each model once before its first live recording: key, "
        "endpoint, one probe request, context, cost (default: on)",
        ("on", "off"),
    ),
)


@dataclass(frozen=True)
class RunSettings:
    """Everything the EMRD plugin was asked to do, after precedence and validation."""

    models: tuple[str, ...]
    conditions: tuple[str, ...]
    cells: tuple[tuple[str, str], ...]
    """``(model, condition)`` pairs the run covers: every selected model under every selected
    condition, or :data:`DEFAULT_CELLS` (filtered by any ``--emrd-condition``) when no model
    was selected."""
    spawns: tuple[str, ...]
    episodes: int
    variant: str
    layouts: str
    backend: str
    backend_options: tuple[tuple[str, Any], ...]
    """``(key, value)`` pairs handed to the backend's simulator, in the order given."""
    modality: str | None
    """``None``: each model's registry default."""
    record_mode: str
    matching: str
    results: Path | None
    """Run directory to resume, or ``None`` for a fresh one."""
    thresholds: Path | None
    """``None``: a run without gates (none given, no ``<rootdir>/thresholds.yaml``)."""
    models_file: Path | None
    cassettes: Path
    shard: tuple[int, int] | None
    """``(k, n)``: this run covers the k-th of n slices (1-based)."""
    concurrency: int = 1
    preflight: bool = True

    @property
    def replays_only(self) -> bool:
        """Record mode ``none``: no episode calls a model (nothing to preflight)."""
        return self.record_mode == "none"

    @property
    def backend_kwargs(self) -> dict[str, Any]:
        """:attr:`backend_options` as keyword arguments (a later key overrides an earlier one)."""
        return dict(self.backend_options)


def parse_shard(text: str) -> tuple[int, int]:
    """``"2/4"`` -> ``(2, 4)``; :class:`ConfigError` unless ``1 <= K <= N``."""
    k_text, sep, n_text = text.partition("/")
    if not (sep and k_text.strip().isdigit() and n_text.strip().isdigit()):
        raise ConfigError(f"--emrd-shard={text!r} must look like K/N, e.g. --emrd-shard=2/4.")
    k, n = int(k_text), int(n_text)
    if n < 1:
        raise ConfigError(
            f"--emrd-shard={text!r} splits the episodes into N={n} slices; N must be at "
            "least 1, e.g. --emrd-shard=1/4 for the first of four slices."
        )
    if not 1 <= k <= n:
        raise ConfigError(
            f"--emrd-shard={text!r} needs 1 <= K <= N; the slices of N={n} are "
            f"--emrd-shard=1/{n} to --emrd-shard={n}/{n}."
        )
    return k, n


def parse_backend_option(text: str) -> tuple[str, Any]:
    """``"gpu_device=1"`` -> ``("gpu_device", 1)``: the value as JSON if it parses, else text."""
    key, sep, value = text.partition("=")
    key = key.strip()
    if not (sep and key.isidentifier()):
        raise ConfigError(
            f"--emrd-backend-option={text!r} must look like KEY=VALUE with KEY a Python "
            "identifier, e.g. --emrd-backend-option=gpu_device=1."
        )
    try:
        return key, json.loads(value)
    except json.JSONDecodeError:
        return key, value


def in_ci(env: Mapping[str, str]) -> bool:
    """``CI`` is set to something that means yes (``false``, ``0``, ``no``, empty mean no)."""
    return env.get("CI", "").strip().lower() not in _NOT_CI


def _matching(raw: Any, backend: str) -> str:
    if raw is None:
        return "lenient" if backend in LENIENT_BACKENDS else "strict"
    if raw == "strict" and backend in LENIENT_BACKENDS:
        warnings.warn(
            MatchingWarning(
                f"--emrd-matching=strict with --emrd-backend={backend}: {backend} frames are "
                "not bit-stable across GPUs, drivers and builds, so a replay on another "
                "machine will fail as drift; drop --emrd-matching to use lenient matching."
            ),
            stacklevel=3,
        )
    return str(raw)


def _pick(option: Option, cli: Mapping[str, Any], ini: Mapping[str, Any]) -> Any:
    value = cli.get(option.name)
    if value in (None, []):
        value = ini.get(option.name)
    if value in (None, "", []):
        return None
    if option.choices and not option.repeatable:  # a repeatable option's items: _listed
        check_choice(option.flag, value, option.choices)
    return value


def _listed(option: Option, value: Any) -> tuple[str, ...]:
    """The items given (comma-separated or repeated, in order, once each), else every choice."""
    if value is None:
        return option.choices or ()
    items = [part.strip() for item in value for part in str(item).split(",") if part.strip()]
    if option.choices:
        for item in items:
            check_choice(option.flag, item, option.choices)
    return tuple(dict.fromkeys(items))


def _path(value: Any, base: Path) -> Path:
    path = Path(str(value)).expanduser()
    return path if path.is_absolute() else base / path


def resolve_settings(
    cli: Mapping[str, Any],
    ini: Mapping[str, Any],
    *,
    rootdir: Path,
    env: Mapping[str, str] | None = None,
) -> RunSettings:
    """Apply command line > ini > default, validate, and freeze. ``cli`` and ``ini`` map option
    names to raw values (``None``/empty when not given); relative paths are resolved against
    ``rootdir``. Warns :class:`MatchingWarning` for ``strict`` on a backend not bit-stable.

    :param cli: Option name -> command-line value.
    :param ini: Option name -> ini value.
    :param rootdir: The pytest rootdir.
    :param env: The environment; None for ``os.environ``.
    :returns: The frozen :class:`RunSettings`.
    """
    env = os.environ if env is None else env
    by_name = {o.name: o for o in OPTIONS}
    raw = {name: _pick(option, cli, ini) for name, option in by_name.items()}
    episodes = _count(
        "--emrd-episodes",
        raw["episodes"],
        MAX_EPISODES,
        "episodes per spawn room (the paper runs 20)",
        "or split a larger study over several run directories.",
    )
    backend = raw["backend"] or "builtin"
    results = raw["results"] and _folder(
        "--emrd-results",
        _path(raw["results"], rootdir),
        "pass a directory (a new one, or a run directory to resume).",
    )
    cassettes = _folder(
        "--emrd-cassettes",
        _path(raw["cassettes"] or "cassettes", rootdir),
        "pass the cassette folder (default: <rootdir>/cassettes).",
    )
    concurrency = _count(
        "--emrd-concurrency",
        raw["concurrency"],
        MAX_CONCURRENCY,
        "threads per process",
        "and add processes with -n N for more.",
    )
    if (concurrency or 1) > 1 and backend != "builtin":
        raise ConfigError(
            f"--emrd-concurrency={concurrency} runs episodes in threads, which the {backend} "
            "backend (one simulator process per worker) does not support; use -n N instead."
        )
    thresholds = _path(raw["thresholds"] or "thresholds.yaml", rootdir)  # the default if it exists
    conditions = _listed(by_name["condition"], raw["condition"])
    if raw["model"] is None:
        cells = tuple((m, c) for m, cs in DEFAULT_CELLS for c in cs if c in conditions)
        models = tuple(dict.fromkeys(m for m, _ in cells))
    else:
        models = _listed(by_name["model"], raw["model"])
        for model in models:
            check_slug("--emrd-model", model, becomes="a model name is a cassette folder")
        cells = tuple((m, c) for m in models for c in conditions)
    return RunSettings(
        models=models,
        conditions=conditions,
        cells=cells,
        spawns=_listed(by_name["spawn"], raw["spawn"]),
        episodes=episodes or 20,
        variant=raw["variant"] or "default",
        layouts=raw["layouts"] or "paper",
        backend=backend,
        backend_options=tuple(parse_backend_option(str(o)) for o in raw["backend_option"] or ()),
        modality=raw["modality"],
        record_mode=raw["record_mode"] or ("none" if in_ci(env) else "once"),
        matching=_matching(raw["matching"], backend),
        results=results,
        thresholds=thresholds if raw["thresholds"] or thresholds.is_file() else None,
        models_file=_path(raw["models"], rootdir) if raw["models"] else None,
        cassettes=cassettes,
        shard=parse_shard(str(raw["shard"])) if raw["shard"] else None,
        concurrency=concurrency or 1,
        preflight=raw["preflight"] != "off",
    )


def _folder(flag: str, folder: Path, fix: str) -> Path:
    """``folder``, unless a file stands at it or at its nearest existing ancestor."""
    existing = folder
    while not existing.exists() and existing != existing.parent:
        existing = existing.parent
    if not existing.is_dir():
        where = "is a file" if existing == folder else f"lies under the file {existing}"
        raise ConfigError(f"{flag}={folder} {where}; {fix}")
    return folder


def _count(flag: str, value: Any, most: int, unit: str, more: str) -> int | None:
    """A whole number from 1 to ``most`` given as text or int, or None when not given."""
    if value is None:
        return None
    text = str(value).strip()
    count = check_positive_int(flag, int(text) if text.isdigit() else text)
    if count > most:
        raise ConfigError(f"{flag}={count} is more than {most} {unit}; pass at most {most}, {more}")
    return count
