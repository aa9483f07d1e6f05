"""``emrd bench``: the product's own speed and size, measured on this machine.

Each stage module (``world``, ``loop``, ``metrics``, ``replay``, ``live``, ``report``,
``plugin``) exposes ``run(*, repeat: int) -> list[Figure]``. Timings are medians over ``repeat``
repetitions after one warm-up; ``--json`` prints the figures as one JSON list.
"""

from __future__ import annotations

import importlib
import resource
import statistics
import subprocess
import time
from collections.abc import Callable, Sequence
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


def run_timed(
    cmd: Sequence[str], *, cwd: Path
) -> tuple[subprocess.CompletedProcess[str], float, float]:
    """Run ``cmd`` (output captured); its result, wall seconds and CPU seconds (user +
    system of every process it waited for, e.g. pytest-xdist workers)."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    done = subprocess.run(cmd, cwd=cwd, capture_output=True, text=True, check=False)
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
