"""pytest glue for pytest-emrd: the ``pytest11`` entry point (``emrd = "pytest_emrd.plugin"``).

A test that requests ``emrd_spec`` is parametrised over the run's episodes, one that requests
``emrd_gate`` over its gates; sessions that collect neither start and write nothing. The
controller hands the run directory and session to xdist workers; the ``emrd_*`` fixtures are
built as pytest-recording builds ``vcr`` (docs/reference/fixtures.md)."""

from __future__ import annotations

import dataclasses
import uuid
import warnings
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

from pytest_emrd._scrub import install_log_scrub, remove_log_scrub, scrub, scrub_report
from pytest_emrd.errors import EmrdError
from pytest_emrd.gate import GateCell, Verdict
from pytest_emrd.plugin._report import RunReport
from pytest_emrd.plugin._run import RUN, Run
from pytest_emrd.run import (
    OPTIONS,
    ResultsStore,
    RunSettings,
    StoredEpisode,
    check_resume,
    new_run_dir,
    resolve_settings,
)
from pytest_emrd.trajectory import EpisodeSpec, Trajectory

__all__ = [
    "emrd_cassette_dir",
    "emrd_episode",
    "emrd_record_mode",
    "emrd_settings",
    "emrd_store",
    "emrd_trajectories",
    "emrd_trajectory",
    "emrd_verdict",
]


def pytest_addoption(parser: pytest.Parser) -> None:
    group = parser.getgroup("emrd", "pytest-emrd (Explore, Map, Remember, Decide benchmark)")
    for option in OPTIONS:
        choices = f" Choices: {', '.join(option.choices)}." if option.choices else ""
        kwargs = option.argparse_kwargs(option.ini)
        group.addoption(option.flag, **{**kwargs, "help": option.help + choices})
        kind = "args" if option.repeatable else "string"
        parser.addini(option.ini, f"{option.help} (ini twin of {option.flag})", kind)


def pytest_configure(config: pytest.Config) -> None:
    cli = {o.name: config.getoption(o.ini) for o in OPTIONS}
    ini = {o.name: config.getini(o.ini) for o in OPTIONS}
    workerinput = getattr(config, "workerinput", None)
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            settings = resolve_settings(cli, ini, rootdir=config.rootpath)
        if settings.results is not None and workerinput is None:
            check_resume(settings.results, settings.shard)
    except EmrdError as exc:
        raise pytest.UsageError(scrub(str(exc))) from None
    for warning in caught if workerinput is None else ():
        config.issue_config_time_warning(warning.message, stacklevel=2)
    if workerinput is not None and "emrd_run_dir" in workerinput:
        run_dir, session = Path(workerinput["emrd_run_dir"]), workerinput["emrd_session"]
    else:
        default = new_run_dir(config.rootpath / ".emrd" / "runs")
        run_dir, session = settings.results or default, uuid.uuid4().hex
    run = Run(config, settings, run_dir, session)
    config.stash[RUN] = run
    config.pluginmanager.register(run, "emrd-run")
    if workerinput is None:  # the controller reports, and names a stopped model's endpoint once
        config.pluginmanager.register(RunReport(run), "emrd-report")
        config.pluginmanager.register(run.endpoints, "emrd-endpoints")


@pytest.hookimpl(optionalhook=True)
def pytest_configure_node(node: Any) -> None:
    """pytest-xdist: every worker shares the controller's run directory and session."""
    run = node.config.stash[RUN]
    node.workerinput["emrd_run_dir"] = str(run.run_dir)
    node.workerinput["emrd_session"] = run.session


def pytest_generate_tests(metafunc: pytest.Metafunc) -> None:
    if "emrd_spec" in metafunc.fixturenames:
        specs = metafunc.config.stash[RUN].call(lambda run: run.episode_specs)
        metafunc.parametrize("emrd_spec", specs, ids=[s.case_id for s in specs])
    if "emrd_gate" in metafunc.fixturenames:
        cells = metafunc.config.stash[RUN].call(lambda run: run.gate_cells)
        metafunc.parametrize("emrd_gate", cells, ids=[c.gate_id for c in cells])


@pytest.hookimpl(trylast=True)
def pytest_collection_modifyitems(
    session: pytest.Session, config: pytest.Config, items: list[pytest.Item]
) -> None:
    """Drop the placeholder items of an empty grid; stop a replay-only run with missing
    cassettes with one summary (after ``-k``)."""
    empty = [item for item in items if _is_empty_emrd_item(item)]
    if empty:
        config.hook.pytest_deselected(items=empty)
        items[:] = [item for item in items if item not in empty]
    summary = config.stash[RUN].call(lambda run: run.missing_summary(items))
    if summary is None:
        return
    if hasattr(config, "workerinput"):  # xdist: the controller prints it once, as the stop reason
        session.shouldfail = summary
        config.hook.pytest_deselected(items=list(items))
        items[:] = []
        return
    raise pytest.UsageError(summary)


@pytest.hookimpl(wrapper=True)
def pytest_runtest_makereport(item: pytest.Item) -> Any:
    """No secret in what the terminal and ``--junitxml`` print for an EMRD test."""
    report = yield
    if any(name.startswith("emrd_") for name in getattr(item, "fixturenames", ())):
        scrub_report(report)
    return report


def _is_empty_emrd_item(item: pytest.Item) -> bool:
    params = getattr(getattr(item, "callspec", None), "params", {})
    for name, kind in (("emrd_gate", GateCell), ("emrd_spec", EpisodeSpec)):
        if name in getattr(item, "fixturenames", ()):
            return not isinstance(params.get(name), kind)
    return False


# The scrub filter on pytest's log handlers, attached whenever they are installed (only while
# a phase runs: at the start of the session, of collection and of each test).
@pytest.hookimpl(tryfirst=True)
def pytest_sessionstart() -> None:
    install_log_scrub()


pytest_collection = pytest_runtest_setup = pytest_sessionstart


def pytest_unconfigure() -> None:
    remove_log_scrub()


@pytest.fixture(scope="session")
def emrd_settings(pytestconfig: pytest.Config) -> RunSettings:
    """The run's settings, resolved from the ``--emrd-*`` options and ini keys. Override it
    to change any setting but the grid (``dataclasses.replace(settings, matching=...)``)."""
    return pytestconfig.stash[RUN].settings


@pytest.fixture(scope="session")
def emrd_cassette_dir(emrd_settings: RunSettings) -> Path:
    """The cassette folder episodes replay from and record into (default: the settings')."""
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
    """``emrd_trajectories(model, condition)``: the trajectories of that cell (custom gates)."""

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
