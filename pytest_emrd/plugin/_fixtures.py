"""The ``emrd_*`` fixtures: settings, store, episodes, trajectories and verdicts of the run."""

from __future__ import annotations

from collections.abc import Callable

import pytest

from pytest_emrd.gate import GateCell, ResultsStore, RunSettings, StoredEpisode, Verdict
from pytest_emrd.plugin._run import RUN
from pytest_emrd.trajectory import EpisodeSpec, Trajectory


@pytest.fixture(scope="session")
def emrd_settings(pytestconfig: pytest.Config) -> RunSettings:
    """The resolved ``--emrd-*`` settings of this run."""
    return pytestconfig.stash[RUN].settings


@pytest.fixture(scope="session")
def emrd_store(pytestconfig: pytest.Config) -> ResultsStore:
    """The results store of this run's directory (shared by all xdist workers)."""
    return pytestconfig.stash[RUN].store


@pytest.fixture
def emrd_episode(
    emrd_spec: EpisodeSpec, pytestconfig: pytest.Config, request: pytest.FixtureRequest
) -> StoredEpisode:
    """The stored episode for ``emrd_spec``, computed (recorded or replayed) if needed."""
    run = pytestconfig.stash[RUN]
    stored = run.episode(emrd_spec)
    request.node.user_properties.append(("emrd_episode", run.summary(stored).to_dict()))
    return stored


@pytest.fixture
def emrd_trajectory(emrd_episode: StoredEpisode) -> Trajectory:
    """The trajectory of ``emrd_spec``."""
    return emrd_episode.trajectory


@pytest.fixture(scope="session")
def emrd_trajectories(pytestconfig: pytest.Config) -> Callable[[str, str], list[Trajectory]]:
    """``emrd_trajectories(model, condition)``: the trajectories of that cell of the run's grid
    (for custom gates), each computed through the results store if needed."""
    run = pytestconfig.stash[RUN]

    def cell(model: str, condition: str) -> list[Trajectory]:
        cell_specs = run.call(lambda r: r.cell_specs_of(model, condition))
        return [run.episode(spec).trajectory for spec in cell_specs]

    return cell


@pytest.fixture
def emrd_verdict(
    emrd_gate: GateCell, pytestconfig: pytest.Config, request: pytest.FixtureRequest
) -> Verdict:
    """The verdict of ``emrd_gate`` over its cell's episodes (computed through the store)."""
    verdict = pytestconfig.stash[RUN].verdict(emrd_gate)
    request.node.user_properties.append(("emrd_verdict", verdict.to_dict()))
    return verdict
