"""``python -m perf report``: ``emrd report`` on a finished 240-episode run directory.

The run directory holds one model x 3 conditions x 4 spawns x 20 episodes of 50 steps from
:mod:`pytest_emrd.metrics.synthetic`, written as the results store writes episodes (built
once, not timed).

* ``report.grid_240_s`` — the whole ``emrd report RUN_DIR --out DIR`` process (interpreter
  start-up, reading the run back, every gate, table and figure, writing Markdown, HTML, JSON
  and the PNGs), wall time, under Python's default bytecode policy (``.pyc`` cached, as on a
  user's machine from the second run on; :func:`~perf.python_env`, warmed up
  before timing): every episode measured, every table and figure fitted. Target 3 s.
  ``report.grid_240_cpu_s``: its CPU time. The figures are drawn in two processes where
  there are two cores.
* ``report.grid_240_nobytecode_s`` — the same command with ``PYTHONDONTWRITEBYTECODE=1``,
  no target.
"""

from __future__ import annotations

import statistics
import sys
import tempfile
from pathlib import Path

from perf import Figure, python_env, run_timed
from pytest_emrd.trajectory import Trajectory

TARGET_GRID_240_S = 3.0


def write_run_dir(run_dir: Path, trajectories: list[Trajectory]) -> None:
    """``trajectories`` stored in ``run_dir`` by the results store, as a pytest run leaves
    them."""
    from pytest_emrd.cassette import EpisodeRun
    from pytest_emrd.run import ResultsStore

    store = ResultsStore(run_dir, session="bench", protocol=trajectories[0].protocol)
    for t in trajectories:
        store.get_or_compute(t.spec, lambda spec, t=t: EpisodeRun(t, False, 0, 0.0))


def run(*, repeat: int, warmup: int) -> list[Figure]:
    from pytest_emrd.metrics.synthetic import synthetic_grid

    cached, uncached = python_env(bytecode=True), python_env(bytecode=False)
    policies = (("", cached), ("_nobytecode", uncached))
    samples: dict[str, list[tuple[float, float]]] = {policy: [] for policy, _ in policies}
    with tempfile.TemporaryDirectory() as tmp:
        run_dir, out = Path(tmp) / "run", Path(tmp) / "report"
        write_run_dir(run_dir, synthetic_grid())
        cmd = [sys.executable, "-m", "pytest_emrd.cli", "report", str(run_dir), "--out", str(out)]
        for i in range(warmup + repeat):  # the warm-up fills the bytecode cache
            for policy, env in policies:
                done, wall, cpu = run_timed(cmd, cwd=Path(tmp), env=env)
                if done.returncode != 0:
                    raise RuntimeError(f"emrd report failed:\n{done.stdout[-2000:]}{done.stderr}")
                if i >= warmup:
                    samples[policy].append((wall, cpu))
    median = statistics.median
    return [
        Figure(
            "report.grid_240_s", median(w for w, _ in samples[""]), "s", TARGET_GRID_240_S, repeat
        ),
        Figure("report.grid_240_cpu_s", median(c for _, c in samples[""]), "s", None, repeat),
        Figure(
            "report.grid_240_nobytecode_s",
            median(w for w, _ in samples["_nobytecode"]),
            "s",
            None,
            repeat,
        ),
    ]
