"""pytest glue for pytest-emrd: the ``pytest11`` entry point (``emrd = "pytest_emrd.plugin"``).

A test that requests ``emrd_spec`` is parametrised over the run's episodes
(``test_episode[scout-low_light-kitchen-ep07]``), one that requests ``emrd_gate`` over its
gates (``test_gate[scout-baseline-aec]``). Sessions that collect neither stay untouched:
nothing is imported, started or written. The only package that imports pytest; one concern
per module: ``_options`` (options, settings, xdist hand-over), ``_collect``, ``_run`` (the
per-process run state), ``_live`` (preflight and live line), ``_report`` (end-of-run tables,
``$GITHUB_STEP_SUMMARY``), ``_fixtures``, ``_logs`` (the scrub filter on log handlers) and
``_endpoint`` (a dead endpoint stops its model)."""

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
from pytest_emrd.plugin._options import pytest_addoption, pytest_configure, pytest_configure_node

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
