"""The ``emrd_*`` fixtures, built the way pytest-recording builds ``vcr``: three overridable
session fixtures and the fixtures derived from them (docs/reference/fixtures.md). The grid
is collected from the ``--emrd-*`` options before any fixture runs, so an override may
change everything but that (see :meth:`~pytest_emrd.plugin._run.Run.adopt`)."""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from pathlib import Path

import pytest

from pytest_emrd.gate import GateCell, Verdict
from pytest_emrd.plugin._run import RUN, Run
from pytest_emrd.run import ResultsStore, RunSettings, StoredEpisode
from pytest_emrd.trajectory import EpisodeSpec, Trajectory


@pytest.fixture(scope="session")
def emrd_settings(pytestconfig: pytest.Config) -> RunSettings:
    """The run's settings, resolved from the ``--emrd-*`` options and ini keys. Override it
    to change any setting but the grid (``dataclasses.replace(settings, matching=...)``)."""
    return pytestconfig.stash[RUN].settings


@pytest.fixture(scope="session")
def emrd_cassette_dir(emrd_settings: RunSettings) -> Path:
    """The cassette folder episodes replay from and record into (``emrd_settings.cassettes``
    unless overridden)."""
    return emrd_settings.cassettes


@pytest.fixture(scope="session")
def emrd_record_mode(emrd_settings: RunSettings) -> str:
    """The cassette record mode (``emrd_settings.record_mode`` unless overridden)."""
    return emrd_settings.record_mode


@pytest.fixture(scope="session")
def _emrd_run(
    pytestconfig: pytest.Config,
    emrd_settings: RunSettings,
    emrd_cassette_dir: Path,
    emrd_record_mode: str,
) -> Run:
    """The process's run, running the collected grid with the three fixtures above."""
    wanted = dataclasses.replace(
        emrd_settings, cassettes=Path(emrd_cassette_dir), record_mode=emrd_record_mode
    )
    return pytestconfig.stash[RUN].call(lambda run: run.adopt(wanted), "emrd_settings")


@pytest.fixture(scope="session")
def emrd_store(_emrd_run: Run) -> ResultsStore:
    """The results store of this run's directory (shared by all xdist workers)."""
    return _emrd_run.store


@pytest.fixture
def emrd_episode(
    emrd_spec: EpisodeSpec, _emrd_run: Run, request: pytest.FixtureRequest
) -> StoredEpisode:
    """The stored episode for ``emrd_spec``, computed (recorded or replayed) if needed."""
    stored = _emrd_run.episode(emrd_spec)
    request.node.user_properties.append(("emrd_episode", _emrd_run.summary(stored).to_dict()))
    return stored


@pytest.fixture
def emrd_trajectory(emrd_episode: StoredEpisode) -> Trajectory:
    """The trajectory of ``emrd_spec``."""
    return emrd_episode.trajectory


@pytest.fixture(scope="session")
def emrd_trajectories(_emrd_run: Run) -> Callable[[str, str], list[Trajectory]]:
    """``emrd_trajectories(model, condition)``: the trajectories of that cell of the run's grid
    (for custom gates), each computed through the results store if needed."""

    def cell(model: str, condition: str) -> list[Trajectory]:
        cell_specs = _emrd_run.call(lambda r: r.cell_specs_of(model, condition))
        return [_emrd_run.episode(spec).trajectory for spec in cell_specs]

    return cell


@pytest.fixture
def emrd_verdict(emrd_gate: GateCell, _emrd_run: Run, request: pytest.FixtureRequest) -> Verdict:
    """The verdict of ``emrd_gate`` over its cell's episodes (computed through the store)."""
    verdict = _emrd_run.verdict(emrd_gate)
    request.node.user_properties.append(("emrd_verdict", verdict.to_dict()))
    return verdict
