"""The validation runner (I/O): a plan's episodes in spawned worker processes, cached on disk.

Episodes go through the results store (:class:`~pytest_emrd.run.ResultsStore`) under
``<out>/episodes/``, reused by the next run with the same protocol, so a rerun only
recomputes the checks. What crosses the process boundary is plain dicts.
"""

from __future__ import annotations

import multiprocessing
import secrets
import time
from collections.abc import Callable
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from pytest_emrd._serde import to_dict
from pytest_emrd.errors import check_positive_int
from pytest_emrd.trajectory import EpisodeSpec, Trajectory
from pytest_emrd.validate._plan import Plan


@dataclass(frozen=True)
class Progress:
    """One finished episode, as the runner reports it."""

    done: int
    total: int
    case_id: str
    status: str
    seconds: float


def _episode(spec: dict[str, Any], run_dir: str, session: str) -> dict[str, Any]:
    """Worker: the stored or freshly computed trajectory of ``spec`` (plain data)."""
    from pytest_emrd.cassette import EpisodeRun
    from pytest_emrd.episode import protocol_version, run_episode
    from pytest_emrd.run import ResultsStore

    def compute(s: EpisodeSpec) -> EpisodeRun:
        start = time.perf_counter()
        trajectory = run_episode(s)
        return EpisodeRun(trajectory, False, 0, time.perf_counter() - start)

    episode = EpisodeSpec(**spec)
    store = ResultsStore(Path(run_dir), session=session, protocol=protocol_version(episode.backend))
    return store.get_or_compute(episode, compute).trajectory.to_dict()


def run_plan(
    plan: Plan, out: Path, *, jobs: int = 2, on_episode: Callable[[Progress], None]
) -> dict[str, list[Trajectory]]:
    """Trajectories of every group of ``plan`` (group name -> spawn-major list); cached
    episodes under ``out`` are reused, the rest run on ``jobs`` processes.

    :param plan: The groups and episodes to run.
    :param out: The folder of cached episodes.
    :param jobs: Worker processes.
    :param on_episode: Called with the :class:`Progress` after each episode.
    :returns: Group name -> its trajectories.
    """
    check_positive_int("jobs", jobs)
    specs = plan.specs()
    session = secrets.token_hex(6)
    by_case: dict[str, Trajectory] = {}
    context = multiprocessing.get_context("spawn")
    start = time.perf_counter()
    with ProcessPoolExecutor(max_workers=jobs, mp_context=context) as pool:
        futures = {pool.submit(_episode, to_dict(s), str(out), session): s.case_id for s in specs}
        for done, future in enumerate(as_completed(futures), start=1):
            trajectory = Trajectory.from_dict(future.result())
            by_case[futures[future]] = trajectory
            elapsed = time.perf_counter() - start
            on_episode(Progress(done, len(specs), futures[future], trajectory.status, elapsed))
    return {g.name: [by_case[s.case_id] for s in g.specs(plan.episodes)] for g in plan.groups}
