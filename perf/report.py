"""``python -m perf report``: ``emrd report`` on a finished 240-episode run directory.

The run directory holds one model x 3 conditions x 4 spawns x 20 episodes of 50 steps from
:mod:`pytest_emrd.metrics.synthetic`, written as the results store writes episodes, with the
per-episode metrics saved beside them as a pytest run leaves them (built once, not timed).

* ``report.grid_240_s`` — the whole ``emrd report RUN_DIR --out DIR`` process (interpreter
  start-up, reading the run back, every gate, table and figure, writing Markdown, HTML, JSON
  and the PNGs), wall time, under Python's default bytecode policy (``.pyc`` cached, as on a
  user's machine from the second run on; :func:`~perf.python_env`, warmed up
  before timing). Target 3 s. ``report.grid_240_cpu_s``: its CPU time.
  The run directory holds the statistics an earlier report saved beside it
  (:mod:`pytest_emrd.report._cache`, written by the untimed warm-up run), as it does from a
  run's second report on; the figures are drawn in two processes where there are two cores.
* ``report.grid_240_first_s`` — the first report of the run: the same command with those
  statistics removed before each run (every table and figure fitted again), no target.
* ``report.grid_240_nobytecode_s`` — the same command as ``grid_240_s`` with
  ``PYTHONDONTWRITEBYTECODE=1``, no target.

A run directory without saved metrics (a run from before they were saved) costs the metrics
of every episode on top: ``metrics.grid_240_s``.
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
    """``trajectories`` stored in ``run_dir`` by the results store, as a finished pytest run
    leaves them: the episodes, their heads and their saved per-episode metrics."""
    from pytest_emrd.cassette import EpisodeRun
    from pytest_emrd.metrics import EpisodeMetrics, episode_metrics
    from pytest_emrd.run import (
        EPISODE_METRICS_CODE,
        EPISODE_METRICS_LIBRARIES,
        MeasuredStore,
        ResultsStore,
        code_fingerprint,
    )

    store = ResultsStore(run_dir, session="bench", protocol=trajectories[0].protocol)
    measured = MeasuredStore(
        store,
        measure=episode_metrics,
        load=EpisodeMetrics.from_dict,
        code=code_fingerprint(EPISODE_METRICS_CODE, EPISODE_METRICS_LIBRARIES),
    )
    by_spec = {t.spec: EpisodeRun(t, False, 0, 0.0) for t in trajectories}
    for spec in by_spec:
        measured.get(spec, lambda s: store.get_or_compute(s, by_spec.__getitem__))


def run(*, repeat: int, warmup: int) -> list[Figure]:
    from pytest_emrd.metrics.synthetic import synthetic_grid
    from pytest_emrd.report._cache import aggregates_path

    cached, uncached = python_env(bytecode=True), python_env(bytecode=False)
    policies = (("", cached), ("_first", cached), ("_nobytecode", uncached))
    samples: dict[str, list[tuple[float, float]]] = {policy: [] for policy, _ in policies}
    with tempfile.TemporaryDirectory() as tmp:
        run_dir, out = Path(tmp) / "run", Path(tmp) / "report"
        write_run_dir(run_dir, synthetic_grid())
        cmd = [sys.executable, "-m", "pytest_emrd.cli", "report", str(run_dir), "--out", str(out)]
        for i in range(warmup + repeat):  # the warm-up fills the bytecode cache
            for policy, env in policies:
                if policy == "_first":
                    aggregates_path(run_dir).unlink()
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
            "report.grid_240_first_s", median(w for w, _ in samples["_first"]), "s", None, repeat
        ),
        Figure(
            "report.grid_240_first_cpu_s",
            median(c for _, c in samples["_first"]),
            "s",
            None,
            repeat,
        ),
        Figure(
            "report.grid_240_nobytecode_s",
            median(w for w, _ in samples["_nobytecode"]),
            "s",
            None,
            repeat,
        ),
    ]
