"""pytest glue for pytest-emrd: the ``pytest11`` entry point (``emrd = "pytest_emrd.plugin"``).

A test that requests ``emrd_spec`` is parametrised over the run's episodes
(``test_episode[scout-low_light-kitchen-ep07]``), one that requests ``emrd_gate`` over its
gates (``test_gate[scout-baseline-aec]``). Sessions that collect neither stay untouched:
nothing is imported, started or written. The controller picks the run directory and the
session id and hands them to pytest-xdist workers through ``workerinput``.

Each process (the only one, or each xdist worker) keeps one simulator per expensive backend
(:class:`~pytest_emrd.episode.SimulatorPool`: one AI2-THOR process per worker, not per
episode), closed at the end of the session. When ``$GITHUB_STEP_SUMMARY`` is set, the
controller appends the run's Markdown summary to that file once the EMRD cases have run.

Wiring only, one concern per module (the only modules of the package that import pytest):

* :mod:`~pytest_emrd.plugin._options` — the ``--emrd-*`` options and ini keys, resolved once
  per process; xdist workers get the controller's run directory and session;
* :mod:`~pytest_emrd.plugin._collect` — parametrisation over episodes and gates, empty grids,
  missing cassettes, scrubbed test reports;
* :mod:`~pytest_emrd.plugin._run` — the per-process run state (registry, grid, store,
  episodes, verdicts), everything heavy built on first use;
* :mod:`~pytest_emrd.plugin._live` — preflight and the live progress line (controller);
* :mod:`~pytest_emrd.plugin._report` — the end-of-run tables and ``$GITHUB_STEP_SUMMARY``
  (controller);
* :mod:`~pytest_emrd.plugin._fixtures` — the ``emrd_*`` fixtures: overridable session
  fixtures and the per-test ones derived from them;
* :mod:`~pytest_emrd.plugin._logs` — the scrub filter on pytest's log handlers and on the
  HTTP libraries' loggers.
"""

from pytest_emrd.plugin._collect import (
    pytest_collection_modifyitems,
    pytest_generate_tests,
    pytest_runtest_makereport,
)
from pytest_emrd.plugin._fixtures import (
    _emrd_run,
    emrd_cassette_dir,
    emrd_episode,
    emrd_record_mode,
    emrd_settings,
    emrd_store,
    emrd_trajectories,
    emrd_trajectory,
    emrd_verdict,
)
from pytest_emrd.plugin._options import (
    pytest_addoption,
    pytest_configure,
    pytest_configure_node,
)

__all__ = [
    "_emrd_run",
    "emrd_cassette_dir",
    "emrd_episode",
    "emrd_record_mode",
    "emrd_settings",
    "emrd_store",
    "emrd_trajectories",
    "emrd_trajectory",
    "emrd_verdict",
    "pytest_addoption",
    "pytest_collection_modifyitems",
    "pytest_configure",
    "pytest_configure_node",
    "pytest_generate_tests",
    "pytest_runtest_makereport",
]
