"""``emrd bench``: the product's own speed and size, measured on this machine.

Each stage module (``world``, ``loop``, ``metrics``, ``replay``, ``live``, ``report``,
``plugin``) exposes ``run(*, repeat: int) -> list[Figure]``. Timings are medians over ``repeat``
repetitions after one warm-up; ``--json`` prints the figures as one JSON list.

Whole-process figures (a pytest session, ``emrd report``) depend on whether Python may cache
bytecode. Their targets are measured under Python's default policy, as on a user's machine from
the second run on (:func:`python_env` with ``bytecode=True``: ``.pyc`` written and read, under a
cache of the bench's own, warmed up before timing); the same commands with
``PYTHONDONTWRITEBYTECODE=1`` are reported beside them as separate ``*_nobytecode_*`` figures,
without a target.
"""

from __future__ import annotations

import importlib
import os
import resource
import statistics
import subprocess
import tempfile
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import asdict, dataclass
from pathlib import Path

from pytest_emrd.errors import check_choice

#: Stage name -> module implementing ``run``. Order is the order of ``emrd bench all``.
STAGES: dict[str, str] = {
    "world": "pytest_emrd.bench.world",
    "loop": "pytest_emrd.bench.loop",
    "metrics": "pytest_emrd.bench.metrics",
    "replay": "pytest_emrd.bench.replay",
    "live": "pytest_emrd.bench.live",
    "plugin": "pytest_emrd.bench.plugin",
    "report": "pytest_emrd.bench.report",
}


@dataclass(frozen=True)
class Figure:
    """One measured figure, as ``emrd bench --json`` prints it."""

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


#: The bytecode cache of the processes the bench times under Python's default policy
#: (``PYTHONPYCACHEPREFIX``): kept between bench runs like a user's ``__pycache__`` folders, and
#: apart from them, so the bench neither reads nor fills the machine's own caches (with
#: ``PYTHONDONTWRITEBYTECODE=1`` set, what sits in ``__pycache__`` next to the sources would
#: otherwise decide how cold the no-bytecode figures are).
BYTECODE_CACHE = Path(tempfile.gettempdir()) / "emrd-bench-pycache"


def python_env(*, bytecode: bool) -> dict[str, str]:
    """This process's environment for a timed child process. ``bytecode=True``: Python's
    default policy, ``.pyc`` (and pytest's rewritten ``.pyc``) written and read under
    :data:`BYTECODE_CACHE`; ``False``: ``PYTHONDONTWRITEBYTECODE=1``, every module without a
    ``.pyc`` next to its source (our editable package, the plugin packages pytest rewrites) is
    compiled again in every process."""
    env = dict(os.environ)
    env.pop("PYTHONPYCACHEPREFIX", None)
    env.pop("PYTHONDONTWRITEBYTECODE", None)
    if bytecode:
        env["PYTHONPYCACHEPREFIX"] = str(BYTECODE_CACHE)
    else:
        env["PYTHONDONTWRITEBYTECODE"] = "1"
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


def run_stages(names: list[str], *, repeat: int) -> list[Figure]:
    """Run the named stages (``all`` expands to every stage) and collect their figures."""
    selected = list(STAGES) if "all" in names else names
    for name in selected:
        check_choice("stage", name, [*STAGES, "all"])
    figures: list[Figure] = []
    for name in selected:
        module = importlib.import_module(STAGES[name])
        figures.extend(module.run(repeat=repeat))
    return figures


def format_table(figures: list[Figure]) -> str:
    """Human-readable table of figures with their targets."""
    lines = [f"{'figure':<40} {'value':>12} {'unit':<6} {'target':>10} {'n':>4}  ok"]
    for f in figures:
        ok = {None: "", True: "yes", False: "NO"}[f.meets_target]
        target = "" if f.target is None else f"{f.target:g}"
        lines.append(f"{f.figure:<40} {f.value:>12.4g} {f.unit:<6} {target:>10} {f.n:>4}  {ok}")
    return "\n".join(lines)
