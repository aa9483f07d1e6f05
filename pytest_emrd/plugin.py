"""pytest glue for pytest-emrd: options, parametrisation, fixtures, summary. Wiring only.

A test that requests ``emrd_spec`` is parametrised over the run's episodes
(``test_episode[scout-low_light-kitchen-ep07]``), one that requests ``emrd_gate`` over its
gates (``test_gate[scout-baseline-aec]``). Sessions that collect neither stay untouched:
nothing is imported, started or written. The controller picks the run directory and the
session id and hands them to pytest-xdist workers through ``workerinput``.

Each process (the only one, or each xdist worker) keeps one simulator per expensive backend
(:class:`~pytest_emrd.episode.SimulatorPool`: one AI2-THOR process per worker, not per
episode), closed at the end of the session. When ``$GITHUB_STEP_SUMMARY`` is set, the
controller appends the run's Markdown summary to that file once the EMRD cases have run.
"""

from __future__ import annotations

import contextlib
import os
import uuid
import warnings
from collections.abc import Callable
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path
from typing import Any

import pytest

from pytest_emrd._scrub import scrub, scrub_report, watch_env
from pytest_emrd.errors import EmrdError
from pytest_emrd.gate import (
    OPTIONS,
    EpisodeSummary,
    GateCell,
    ResultsStore,
    RunIdentity,
    RunSettings,
    StoredEpisode,
    Verdict,
    check_resume,
    new_run_dir,
    resolve_settings,
    start_prefetch,
)
from pytest_emrd.trajectory import EpisodeSpec, Trajectory

_RUN = pytest.StashKey["_Run"]()


def pytest_addoption(parser: pytest.Parser) -> None:
    group = parser.getgroup("emrd", "pytest-emrd (Explore, Map, Remember, Decide benchmark)")
    for option in OPTIONS:
        choices = f" Choices: {', '.join(option.choices)}." if option.choices else ""
        kwargs = option.argparse_kwargs(option.ini)
        group.addoption(option.flag, **{**kwargs, "help": option.help + choices})
        parser.addini(option.ini, f"{option.help} (ini twin of {option.flag})", option.ini_type)


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
    run = _Run(config, settings, run_dir, session)
    config.stash[_RUN] = run
    config.pluginmanager.register(run, "emrd-run")


@pytest.hookimpl(optionalhook=True)
def pytest_configure_node(node: Any) -> None:
    """pytest-xdist: every worker shares the controller's run directory and session."""
    run = node.config.stash[_RUN]
    node.workerinput["emrd_run_dir"] = str(run.run_dir)
    node.workerinput["emrd_session"] = run.session


def pytest_generate_tests(metafunc: pytest.Metafunc) -> None:
    if "emrd_spec" in metafunc.fixturenames:
        specs = metafunc.config.stash[_RUN].call(lambda run: run.episode_specs)
        metafunc.parametrize("emrd_spec", specs, ids=[s.case_id for s in specs])
    if "emrd_gate" in metafunc.fixturenames:
        cells = metafunc.config.stash[_RUN].call(lambda run: run.gate_cells)
        metafunc.parametrize("emrd_gate", cells, ids=[c.gate_id for c in cells])


@pytest.hookimpl(trylast=True)
def pytest_collection_modifyitems(
    session: pytest.Session, config: pytest.Config, items: list[pytest.Item]
) -> None:
    """Drop the placeholder items of an empty grid (a shard's gates, a model without gates);
    stop a replay-only run with missing cassettes with one summary (after ``-k``)."""
    empty = [item for item in items if _is_empty_emrd_item(item)]
    if empty:
        config.hook.pytest_deselected(items=empty)
        items[:] = [item for item in items if item not in empty]
    run = config.stash.get(_RUN, None)
    summary = run.call(lambda r: r.missing_summary(items)) if run and items else None
    if summary is None:
        return
    if hasattr(config, "workerinput"):  # xdist: the controller prints it once, as the stop reason
        session.shouldfail = summary
        config.hook.pytest_deselected(items=list(items))
        items[:] = []
        return
    raise pytest.UsageError(summary)


@pytest.hookimpl(wrapper=True)
def pytest_runtest_makereport(item: pytest.Item, call: pytest.CallInfo[None]) -> Any:
    """No secret in what the terminal and ``--junitxml`` print for an EMRD test."""
    report = yield
    if any(name.startswith("emrd_") for name in getattr(item, "fixturenames", ())):
        scrub_report(report)
    return report


def _is_empty_emrd_item(item: pytest.Item) -> bool:
    callspec = getattr(item, "callspec", None)
    names = getattr(item, "fixturenames", ())
    if "emrd_gate" in names:
        return not isinstance(getattr(callspec, "params", {}).get("emrd_gate"), GateCell)
    if "emrd_spec" in names:
        return not isinstance(getattr(callspec, "params", {}).get("emrd_spec"), EpisodeSpec)
    return False


@dataclass(eq=False)
class _Run:
    """Per-process state of the EMRD run; everything heavy is built on first use."""

    config: pytest.Config
    settings: RunSettings
    run_dir: Path
    session: str

    def __post_init__(self) -> None:
        self.episodes: dict[str, EpisodeSummary] = {}
        self.verdicts: list[Verdict] = []
        self._stored: dict[EpisodeSpec, StoredEpisode] = {}
        self._metrics: dict[str, Any] = {}
        self._prefetch_started, self._prefetcher = False, None
        self._ticker: Any = None

    def call(self, fn: Any, what: str = "pytest-emrd") -> Any:
        """``fn(self)``, turning an :class:`EmrdError` into one clean failure line (scrubbed,
        raised outside the ``except``: no "During handling" chain)."""
        try:
            return fn(self)
        except EmrdError as exc:
            message = f"{what}: {scrub(str(exc))}"
        pytest.fail(message, pytrace=False)

    @cached_property
    def registry(self) -> Any:
        from pytest_emrd.agent import load_registry

        registry = load_registry(self.settings.models_file)
        watch_env(config.api_key_env for config in registry.models.values())
        for name in self.settings.models:
            registry.get(name)
        return registry

    @cached_property
    def protocol(self) -> str:
        from pytest_emrd.episode import protocol_version

        return protocol_version(self.settings.backend)

    def modality_of(self, model: str) -> str:
        return str(self.registry.get(model).modality)

    @cached_property
    def episode_specs(self) -> list[EpisodeSpec]:
        from pytest_emrd.gate import episode_specs, shard

        specs = episode_specs(self.settings, self.modality_of)
        return shard(specs, *self.settings.shard) if self.settings.shard else specs

    @cached_property
    def gate_cells(self) -> list[GateCell]:
        from pytest_emrd.gate import gate_cells, load_thresholds
        from pytest_emrd.metrics import GATE_METRICS

        if self.settings.shard or self.settings.thresholds is None:
            return []
        thresholds = load_thresholds(
            self.settings.thresholds, registry=self.registry, metrics=GATE_METRICS
        )
        return gate_cells(self.settings, thresholds)

    @cached_property
    def store(self) -> ResultsStore:
        identity = RunIdentity.of(self.settings, self.protocol)
        return ResultsStore(
            self.run_dir, session=self.session, protocol=self.protocol, identity=identity
        )

    @cached_property
    def invocation(self) -> Any:
        """What printed ``pytest`` commands carry: this run's test paths, registry, options."""
        from pytest_emrd.cassette import Invocation

        return Invocation.of(self.settings, paths=tuple(self.config.args))

    def missing_summary(self, items: list[pytest.Item]) -> str | None:
        """In record mode ``none``: one message for the episodes the selected items need
        that have neither a cassette nor a stored result, or ``None``."""
        from pytest_emrd.cassette import missing_cassettes, missing_summary

        if self.settings.record_mode != "none":
            return None
        needed: dict[EpisodeSpec, None] = {}
        for item in items:
            params = getattr(getattr(item, "callspec", None), "params", {})
            if isinstance(spec := params.get("emrd_spec"), EpisodeSpec):
                needed[spec] = None
            elif isinstance(cell := params.get("emrd_gate"), GateCell):
                needed.update(dict.fromkeys(self.cell_specs(cell)))
        missing = [
            spec
            for spec in missing_cassettes(list(needed), self.settings.cassettes)
            if not self.store.path_for(spec).is_file()
        ]
        if not missing:
            return None
        return missing_summary(
            missing, total=len(needed), root=self.settings.cassettes, invocation=self.invocation
        )

    @cached_property
    def simulators(self) -> Any:
        from pytest_emrd.episode import SimulatorPool

        return SimulatorPool(self.settings.backend_kwargs)

    @cached_property
    def runner(self) -> Any:
        """Runs an episode on this process's simulator pool, one model client per key mode."""
        from pytest_emrd.cassette import agent_runner

        return agent_runner(self.registry, run=self.simulators.run)

    @cached_property
    def status_file(self) -> Any:
        """This process's live status (``<run>/live/<worker>.json``) for the live line."""
        from pytest_emrd.progress import StatusFile

        return StatusFile(self.run_dir)

    def episode(self, spec: EpisodeSpec) -> StoredEpisode:
        from pytest_emrd.cassette import FrameDriftWarning
        from pytest_emrd.progress import run_watched

        settings = self.settings

        def compute(s: EpisodeSpec) -> Any:
            return run_watched(
                s,
                self.runner,
                status=self.status_file,
                cassettes=settings.cassettes,
                protocol=self.protocol,
                record_mode=settings.record_mode,
                matching=settings.matching,
                invocation=self.invocation,
            )

        if spec in self._stored:
            return self._stored[spec]
        if not self._prefetch_started:  # --emrd-concurrency: live episodes ahead, in threads
            self._prefetch_started = True
            self._prefetcher = start_prefetch(settings, self.store, compute, self.episode_specs)
        stored = self.call(lambda run: run.store.get_or_compute(spec, compute), spec.case_id)
        self._stored[spec] = stored
        if stored.frame_drift and stored.computed_now:
            warnings.warn(
                FrameDriftWarning(
                    f"{spec.case_id}: {stored.frame_drift} request(s) matched on text while "
                    "their frames differ from the recording (lenient matching)."
                ),
                stacklevel=2,
            )
        return stored

    def cell_specs(self, cell: GateCell) -> list[EpisodeSpec]:
        return self.cell_specs_of(cell.bound.model, cell.bound.condition)

    def cell_specs_of(self, model: str, condition: str) -> list[EpisodeSpec]:
        from pytest_emrd.errors import check_choice
        from pytest_emrd.gate import cell_specs
        from pytest_emrd.trajectory import CONDITIONS

        self.registry.get(model)
        check_choice("condition", condition, CONDITIONS)
        return cell_specs(self.settings, model, condition, self.modality_of)

    def verdict(self, cell: GateCell) -> Verdict:
        from pytest_emrd.gate import evaluate_cell
        from pytest_emrd.metrics import GATE_METRICS

        trajectories = [self.episode(spec).trajectory for spec in self.cell_specs(cell)]
        return evaluate_cell(cell, trajectories, GATE_METRICS, prepare=self.episode_metrics)

    def episode_metrics(self, trajectory: Trajectory) -> Any:
        """Per-episode metrics, computed once per process (every gate of a cell reuses them)."""
        from pytest_emrd.metrics import episode_metrics

        key = trajectory.spec.case_id
        if key not in self._metrics:
            self._metrics[key] = episode_metrics(trajectory)
        return self._metrics[key]

    def summary(self, stored: StoredEpisode) -> EpisodeSummary:
        config = self.registry.get(stored.trajectory.spec.model)
        return EpisodeSummary.of(
            stored, price_in=config.price_per_mtok_in, price_out=config.price_per_mtok_out
        )

    # -- preflight and the live line (controller only: the only process, or xdist's) -------

    def pytest_collection_finish(self, session: pytest.Session) -> None:
        if hasattr(self.config, "workerinput") or self.config.option.collectonly:
            return
        names = ("emrd_spec", "emrd_gate")
        params = [getattr(i, "callspec", None) for i in session.items]
        self.preflight([c.params[n] for c in params if c for n in names if n in c.params])

    @pytest.hookimpl(optionalhook=True)
    def pytest_xdist_node_collection_finished(self, node: Any, ids: list[str]) -> None:
        from pytest_emrd.preflight import params_of_node_ids

        if self.config.option.collectonly:
            return

        def by_id() -> dict[str, Any]:
            cells = {c.gate_id: c for c in self.call(lambda run: run.gate_cells)}
            return {**cells, **{s.case_id: s for s in self.call(lambda r: r.episode_specs)}}

        self.preflight(params_of_node_ids(ids, by_id))

    @cached_property
    def preflights(self) -> Any:
        from pytest_emrd.preflight import SessionPreflight

        settings = self.settings
        return SessionPreflight(
            self.registry,
            cassettes=settings.cassettes,
            record_mode=settings.record_mode,
            holds=self.store.holds,
            enabled=settings.preflight,
        )

    def preflight(self, params: list[Any]) -> None:
        """Preflight each model the selected tests will call live; a failure ends the session
        before any episode runs. Then start the live line."""
        from pytest_emrd.progress import LiveBoard, Ticker

        if not params:
            return
        cells = (self.cell_specs(p) if isinstance(p, GateCell) else [p] for p in params)
        specs = [spec for group in cells for spec in group]
        reports, live = self.call(lambda run: run.preflights.run(specs))
        for line in (line for report in reports for line in report.lines()):
            self._write_line(line)
        failed = next((r for r in reports if r.failed), None)
        if failed is not None:
            message = scrub(f"pytest-emrd: {failed.message()}")
            pytest.exit(message, returncode=pytest.ExitCode.USAGE_ERROR)
        if live and self._ticker is None:
            board = LiveBoard(self.run_dir, total=live)
            self._ticker = Ticker(board, self._write_line).start()

    def _write_line(self, line: str) -> None:
        """A line on the terminal, also from the live line's thread while a test runs (with
        capture suspended, as pytest's own live logging does)."""
        reporter = self.config.pluginmanager.get_plugin("terminalreporter")
        capture = self.config.pluginmanager.get_plugin("capturemanager")
        if reporter is None:
            return
        with capture.global_and_fixture_disabled() if capture else contextlib.nullcontext():
            if getattr(getattr(reporter, "_tw", None), "width_of_current_line", 0):
                reporter.write("\n")  # after a row of progress dots
            reporter.write_line(scrub(line))

    def pytest_unconfigure(self) -> None:
        # Simulators first: an ai2thor one owns a Unity process, which must not outlive a
        # worker that xdist kills when its teardown runs past the exit timeout.
        if "simulators" in self.__dict__:
            self.simulators.close()
        if self._prefetcher is not None:
            self._prefetcher.close()
        if "runner" in self.__dict__:
            self.runner.close()

    # -- reporting hooks (run in the controller, or the only process without xdist) --------

    def pytest_runtest_logreport(self, report: pytest.TestReport) -> None:
        if report.when != "call":
            return
        props = dict(report.user_properties)
        if "emrd_verdict" in props:
            self.verdicts.append(Verdict.from_dict(props["emrd_verdict"]))
        if "emrd_episode" not in props:
            return
        summary = EpisodeSummary.from_dict(props["emrd_episode"])
        self.episodes[summary.case] = summary
        reporter = self.config.pluginmanager.get_plugin("terminalreporter")
        if summary.recorded and reporter is not None and not hasattr(self.config, "workerinput"):
            reporter.ensure_newline()
            reporter.write_line(summary.progress_line(len(self.episodes)))

    def pytest_sessionfinish(self) -> None:
        """Stop the live line; append the run's Markdown to ``$GITHUB_STEP_SUMMARY``
        (controller only)."""
        if self._ticker is not None:
            self._ticker.stop()
            self._ticker = None
        if not os.environ.get("GITHUB_STEP_SUMMARY") or hasattr(self.config, "workerinput"):
            return
        if not (self.episodes or self.verdicts) or not (self.run_dir / "episodes").is_dir():
            return
        from pytest_emrd.gate import load_run_dirs
        from pytest_emrd.report import append_step_summary, step_summary_markdown

        source = self.settings.thresholds
        if source is not None and source.is_relative_to(self.config.rootpath):
            source = source.relative_to(self.config.rootpath)
        try:
            trajectories = load_run_dirs([self.run_dir])
        except EmrdError as exc:
            warnings.warn(f"pytest-emrd wrote no step summary: {exc}", stacklevel=1)
            return
        append_step_summary(
            step_summary_markdown(
                trajectories, self.verdicts, thresholds_source=source and str(source)
            )
        )

    def pytest_terminal_summary(self, terminalreporter: Any) -> None:
        from pytest_emrd.gate import gate_tables, usage_rows, usage_table

        if not (self.episodes or self.verdicts):
            return
        tr = terminalreporter
        tr.section("EMRD gates" if self.verdicts else "EMRD episodes")
        for line in gate_tables(self.verdicts):
            tr.write_line(line, red=line.lstrip().startswith("FAIL"))
        if self.episodes:
            tr.write_line("tokens per model:")
            for line in usage_table(usage_rows(self.episodes.values())):
                tr.write_line(line)
        tr.write_line(
            f"results: {self.run_dir} (resume: --emrd-results {self.run_dir}; "
            f"gates over shards: emrd gate {self.run_dir} ...)"
        )


# -- fixtures ------------------------------------------------------------------------------


@pytest.fixture(scope="session")
def emrd_settings(pytestconfig: pytest.Config) -> RunSettings:
    """The resolved ``--emrd-*`` settings of this run."""
    return pytestconfig.stash[_RUN].settings


@pytest.fixture(scope="session")
def emrd_store(pytestconfig: pytest.Config) -> ResultsStore:
    """The results store of this run's directory (shared by all xdist workers)."""
    return pytestconfig.stash[_RUN].store


@pytest.fixture
def emrd_episode(
    emrd_spec: EpisodeSpec, pytestconfig: pytest.Config, request: pytest.FixtureRequest
) -> StoredEpisode:
    """The stored episode for ``emrd_spec``, computed (recorded or replayed) if needed."""
    run = pytestconfig.stash[_RUN]
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
    run = pytestconfig.stash[_RUN]

    def cell(model: str, condition: str) -> list[Trajectory]:
        cell_specs = run.call(lambda r: r.cell_specs_of(model, condition))
        return [run.episode(spec).trajectory for spec in cell_specs]

    return cell


@pytest.fixture
def emrd_verdict(
    emrd_gate: GateCell, pytestconfig: pytest.Config, request: pytest.FixtureRequest
) -> Verdict:
    """The verdict of ``emrd_gate`` over its cell's episodes (computed through the store)."""
    verdict = pytestconfig.stash[_RUN].verdict(emrd_gate)
    request.node.user_properties.append(("emrd_verdict", verdict.to_dict()))
    return verdict
