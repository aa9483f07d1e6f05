"""The product's own speed and size, measured on this machine: ``python -m perf``.

The harness lives beside the package, not in it: ``pip install pytest-emrd`` never ships it.
Each stage module (``world``, ``loop``, ``metrics``, ``replay``, ``live``, ``plugin``,
``report``) exposes ``run(*, repeat: int, warmup: int) -> list[Figure]``: medians over
``repeat`` repetitions after ``warmup`` untimed ones.

Every figure is measured twice (:mod:`perf.__main__`):

* **warm** — in this process, after one warm-up: code imported, bytecode cached, as on a
  developer's machine from the second run on;
* **cold** (``<figure>_cold``) — the same stage run with no warm-up in a fresh process on a
  fresh copy of the checkout (:func:`cold_figures`): no bytecode of the product, no run
  directory, as a CI job that has just cloned the repository. Where a stage
  runs several commands in a row (a replay, then the same replay resumed), only its first
  measurement starts from empty caches; the later ones see what the first left behind, as
  the second command of that CI job would.

Whole-process figures (a pytest session, ``emrd report``) depend on whether Python may cache
bytecode. Warm, they are timed under Python's default policy with a bytecode cache of the
harness's own (:func:`python_env` with ``bytecode=True``), filled by the warm-up; the same
commands with ``PYTHONDONTWRITEBYTECODE=1`` are reported beside them as ``*_nobytecode_*``
figures, without a target.
"""

from __future__ import annotations

import importlib
import json
import os
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

from pytest_emrd.errors import check_choice

#: Stage name -> module implementing ``run``, in the order of ``python -m perf all``.
STAGES: dict[str, str] = {
    "world": "perf.world",
    "loop": "perf.loop",
    "metrics": "perf.metrics",
    "replay": "perf.replay",
    "live": "perf.live",
    "plugin": "perf.plugin",
    "report": "perf.report",
}


@dataclass(frozen=True)
class Figure:
    """One measured figure, as ``python -m perf --json`` prints it."""

    figure: str
    """``<stage>.<name>``, e.g. ``world.step_ms``."""
    value: float
    unit: str
    """``ms``, ``s``, ``KB`` or ``ratio``."""
    target: float | None
    """The issue's target for this figure, or None."""
    n: int
    """Repetitions behind the median (1 for sizes)."""
    higher_is_better: bool = False
    """The target is a floor (e.g. a size ratio), not a ceiling."""

    def to_dict(self) -> dict[str, object]:
        return asdict(self)

    @property
    def meets_target(self) -> bool | None:
        if self.target is None:
            return None
        if self.higher_is_better:
            return self.value >= self.target
        return self.value <= self.target


def median_seconds(fn: Callable[[], object], *, repeat: int, warmup: int = 1) -> float:
    """Median wall time of ``fn()`` in seconds over ``repeat`` runs after ``warmup`` runs."""
    for _ in range(warmup):
        fn()
    samples = []
    for _ in range(repeat):
        start = time.perf_counter()
        fn()
        samples.append(time.perf_counter() - start)
    return statistics.median(samples)


def paired_ratio(
    numerator: Callable[[], object],
    denominator: Callable[[], object],
    *,
    repeat: int,
    warmup: int = 1,
) -> float:
    """Median over ``repeat`` pairs of ``cpu(numerator) / cpu(denominator)``, the two run
    back to back in each pair (after ``warmup`` runs of each). Both sides are CPU-bound and
    single-threaded, so their cost is measured as this process's CPU time: other load on
    the machine (which stretches wall time unevenly) does not enter the ratio."""
    for _ in range(warmup):
        numerator()
        denominator()
    ratios = []
    for _ in range(repeat):
        start = time.process_time()
        numerator()
        middle = time.process_time()
        denominator()
        ratios.append((middle - start) / (time.process_time() - middle))
    return statistics.median(ratios)


#: Set (to ``1``) in the environment of a cold stage's process: the commands it times then
#: follow Python's default bytecode policy in the fresh copy, with no cache of the harness's.
COLD_ENV = "EMRD_PERF_COLD"

#: The bytecode cache of the processes the warm figures time under Python's default policy
#: (``PYTHONPYCACHEPREFIX``): kept between harness runs like a user's ``__pycache__`` folders,
#: and apart from them, so the harness neither reads nor fills the machine's own caches.
BYTECODE_CACHE = Path(tempfile.gettempdir()) / "emrd-perf-pycache"

#: The checkout this harness measures (the parent of ``perf/``).
ROOT = Path(__file__).resolve().parents[1]


def python_env(*, bytecode: bool) -> dict[str, str]:
    """This process's environment for a timed child process. ``bytecode=True``: Python's
    default policy, ``.pyc`` written and read (warm: under :data:`BYTECODE_CACHE`; cold:
    beside the fresh copy's sources); ``False``: ``PYTHONDONTWRITEBYTECODE=1``, every module
    without a ``.pyc`` next to its source (our editable package, the plugin packages pytest
    rewrites) is compiled again in every process."""
    env = dict(os.environ)
    env.pop("PYTHONPYCACHEPREFIX", None)
    env.pop("PYTHONDONTWRITEBYTECODE", None)
    if not bytecode:
        env["PYTHONDONTWRITEBYTECODE"] = "1"
    elif not env.get(COLD_ENV):
        env["PYTHONPYCACHEPREFIX"] = str(BYTECODE_CACHE)
    return env


def run_timed(
    cmd: Sequence[str], *, cwd: Path, env: Mapping[str, str] | None = None
) -> tuple[subprocess.CompletedProcess[str], float, float]:
    """Run ``cmd`` (output captured, in ``env`` or this process's environment); its result,
    wall seconds and CPU seconds (user + system of every process it waited for, e.g.
    pytest-xdist workers)."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    done = subprocess.run(cmd, cwd=cwd, env=env, capture_output=True, text=True, check=False)
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return done, wall, cpu


def selected_stages(names: Sequence[str]) -> list[str]:
    """``names`` checked against :data:`STAGES`, ``all`` expanded to every stage."""
    for name in names:
        check_choice("stage", name, [*STAGES, "all"])
    return list(STAGES) if "all" in names else list(dict.fromkeys(names))


def run_stages(names: Sequence[str], *, repeat: int, warmup: int = 1) -> list[Figure]:
    """Run the named stages in this process (``all``: every stage) and collect their
    figures: the warm figures, or with ``warmup=0`` in a fresh copy the cold ones."""
    figures: list[Figure] = []
    for name in selected_stages(names):
        module = importlib.import_module(STAGES[name])
        figures.extend(module.run(repeat=repeat, warmup=warmup))
    return figures


#: What a fresh clone holds that a stage reads; ``cassettes`` is linked, not copied (data only).
_COPIED = ("pytest_emrd", "perf", "benchmarks", "pyproject.toml", "thresholds.yaml")
_NOT_COPIED = shutil.ignore_patterns("__pycache__", "*.pyc", ".emrd")


def fresh_copy(root: Path, into: Path) -> Path:
    """The sources of ``root`` copied into ``into/checkout`` without any bytecode (the
    cassettes linked): what ``git clone`` gives a CI job."""
    copy = into / "checkout"
    copy.mkdir()
    for name in _COPIED:
        source = root / name
        if source.is_dir():
            shutil.copytree(source, copy / name, ignore=_NOT_COPIED)
        else:
            shutil.copy2(source, copy / name)
    (copy / "cassettes").symlink_to(root / "cassettes", target_is_directory=True)
    return copy


def cold_env(copy: Path) -> dict[str, str]:
    """The environment of a cold stage: the copy first on the import path, default bytecode
    policy, :data:`COLD_ENV` set."""
    env = dict(os.environ)
    for name in ("PYTHONPYCACHEPREFIX", "PYTHONDONTWRITEBYTECODE"):
        env.pop(name, None)
    env["PYTHONPATH"] = os.pathsep.join([str(copy), *filter(None, [env.get("PYTHONPATH")])])
    env[COLD_ENV] = "1"
    return env


def cold_figures(names: Sequence[str], *, repeat: int, root: Path = ROOT) -> list[Figure]:
    """Each named stage run ``repeat`` times, each time in a fresh process on a
    :func:`fresh_copy` of ``root`` with no warm-up; per figure the median, named
    ``<figure>_cold`` with ``n`` the number of fresh processes."""
    figures: list[Figure] = []
    for name in selected_stages(names):
        runs: list[list[dict[str, object]]] = []
        for _ in range(repeat):
            with tempfile.TemporaryDirectory(prefix="emrd-perf-cold-") as tmp:
                copy = fresh_copy(root, Path(tmp))
                cmd = [sys.executable, "-m", "perf", name, "--mode", "warm", "--warmup", "0"]
                done = subprocess.run(
                    [*cmd, "--repeat", "1", "--json"],
                    cwd=copy,
                    env=cold_env(copy),
                    capture_output=True,
                    text=True,
                    check=False,
                )
            if done.returncode != 0:
                raise RuntimeError(f"cold stage {name} failed:\n{done.stderr[-3000:]}")
            runs.append(json.loads(done.stdout))
        for i, first in enumerate(runs[0]):
            value = statistics.median(float(str(run[i]["value"])) for run in runs)
            figures.append(
                Figure(
                    f"{first['figure']}_cold",
                    value,
                    str(first["unit"]),
                    None if first["target"] is None else float(str(first["target"])),
                    repeat,
                    bool(first["higher_is_better"]),
                )
            )
    return figures


def format_table(figures: list[Figure]) -> str:
    """Human-readable table of figures with their targets."""
    lines = [f"{'figure':<40} {'value':>12} {'unit':<6} {'target':>10} {'n':>4}  ok"]
    for f in figures:
        ok = {None: "", True: "yes", False: "NO"}[f.meets_target]
        target = "" if f.target is None else f"{f.target:g}"
        lines.append(f"{f.figure:<40} {f.value:>12.4g} {f.unit:<6} {target:>10} {f.n:>4}  {ok}")
    return "\n".join(lines)


def run_with_cassette(spec: Any, run: Callable[..., Any], **tape: Any) -> Any:
    """``run(spec, live=...)`` in each take of ``spec``'s :class:`~pytest_emrd.cassette.Tape`
    (built with ``tape``): a loop of one's own with the product's cassette handling."""
    from pytest_emrd.cassette import Tape

    taken = Tape(spec, **tape)
    for take in taken.takes():
        with take:
            take.trajectory = run(spec, live=taken.live)
    return take.result
