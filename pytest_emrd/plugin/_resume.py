"""A finished run resumed without xdist workers (controller only, before xdist starts them).

Under ``-n N`` pytest-xdist starts N worker processes, each starting pytest, importing the
plugins and collecting the tests again, before the first test runs. When ``--emrd-results``
names a run directory that already holds everything the run's grid needs (every episode
reusable, every gate's per-episode metrics saved for the episode file stored now), no worker
would compute anything: the controller then switches distribution off (as ``-n 0`` does) and
runs the tests itself. They are the same tests with the same outcomes: each episode test still
checks its episode against the store, each gate is evaluated again from the saved metrics, and
the gate table, JUnit XML and exit status are those of a distributed run. Anything to compute
(a missing, stale, errored or unreadable episode, metrics not saved) keeps the distributed run.
"""

from __future__ import annotations

import warnings

import pytest

from pytest_emrd.errors import EmrdError
from pytest_emrd.plugin._run import Run


def local_workers(config: pytest.Config) -> bool:
    """Whether pytest-xdist is about to start workers for this session that share out its
    tests (``-n N``: local processes of this interpreter; not ``--dist each``, not other
    ``--tx`` environments), in the controller."""
    option = config.option
    dist, tx = getattr(option, "dist", "no"), getattr(option, "tx", None)
    if dist in ("no", "each") or not tx or set(tx) != {"popen"}:
        return False
    return not option.collectonly and not hasattr(config, "workerinput")


class InProcessResume:
    """Reports, in the session header, that a finished run directory runs without workers."""

    def __init__(self, run: Run, workers: int) -> None:
        self.run, self.workers = run, workers

    def pytest_report_header(self) -> str:
        return (
            f"emrd: {self.run.run_dir} holds every episode and metric of the run: its tests "
            f"run in this process (no xdist worker started for -n {self.workers})"
        )

    def pytest_collection_finish(self, session: pytest.Session) -> None:
        """Say so when the session also collected tests that are not EMRD tests: they run in
        this process too, without the workers they were given."""
        others = [i for i in session.items if not _is_emrd(i)]
        if others:
            warnings.warn(
                pytest.PytestWarning(
                    f"pytest-emrd: {len(others)} non-EMRD test(s) (e.g. {others[0].nodeid}) "
                    f"run in this process with the finished EMRD run, not in -n "
                    f"{self.workers} workers; give only the EMRD test paths to keep the "
                    "workers for them."
                ),
                stacklevel=1,
            )


def _is_emrd(item: pytest.Item) -> bool:
    params = getattr(getattr(item, "callspec", None), "params", {})
    return "emrd_spec" in params or "emrd_gate" in params


def resume_in_process(config: pytest.Config, run: Run) -> None:
    """Switch xdist off for this session when ``run`` has nothing left to compute (called
    from ``pytest_configure``, which runs before xdist's)."""
    if run.settings.results is None or not local_workers(config):
        return
    try:
        if not run.finished():
            return
    except EmrdError:
        return  # the distributed run reports it, as it would have
    option = config.option
    workers = len(option.tx)
    option.numprocesses, option.dist, option.tx = 0, "no", []
    config.pluginmanager.register(InProcessResume(run, workers), "emrd-resume")
