"""What the controller (the only process, or xdist's) shows: preflight and the live line
while the run goes (each model the selected tests call live is preflighted once, and a
failure ends the session before any episode runs), a progress line per recorded episode,
the gate and token tables and ``$GITHUB_STEP_SUMMARY`` at the end."""

from __future__ import annotations

import contextlib
import os
import warnings
from functools import cached_property
from typing import Any

import pytest

from pytest_emrd._scrub import scrub
from pytest_emrd.errors import EmrdError
from pytest_emrd.gate import Verdict, gate_tables, usage_table
from pytest_emrd.plugin._run import Run, emrd_params, failure_line
from pytest_emrd.progress import LiveBoard, Ticker
from pytest_emrd.run import EpisodeSummary, load_run_episodes, usage_rows


class RunReport:
    """The controller's preflight and live line for one :class:`Run`, and the EMRD tests'
    results (``user_properties``), printed as they come and at the end (registered on the
    controller only: an xdist worker has no terminal to show them on)."""

    def __init__(self, run: Run) -> None:
        self.run = run
        self.config = run.config
        self._ticker: Ticker | None = None
        self.episodes: dict[str, EpisodeSummary] = {}
        self.verdicts: list[Verdict] = []

    def pytest_collection_finish(self, session: pytest.Session) -> None:
        if self.config.option.collectonly:
            return
        self.preflight(emrd_params(session.items))

    @pytest.hookimpl(optionalhook=True)
    def pytest_xdist_node_collection_finished(self, ids: list[str]) -> None:
        if self.config.option.collectonly or self.run.settings.replays_only:
            return
        from pytest_emrd.preflight import params_of_node_ids

        run = self.run

        def by_id() -> dict[str, Any]:
            cells = {c.gate_id: c for c in run.call(lambda r: r.gate_cells)}
            return {**cells, **{s.case_id: s for s in run.call(lambda r: r.episode_specs)}}

        self.preflight(params_of_node_ids(ids, by_id))

    @cached_property
    def preflights(self) -> Any:
        from pytest_emrd.preflight import SessionPreflight

        run = self.run
        settings = run.settings
        return SessionPreflight(
            run.registry,
            cassettes=settings.cassettes,
            record_mode=settings.record_mode,
            holds=run.store.holds,
            enabled=settings.preflight,
            models_file=settings.models_file,
        )

    def preflight(self, params: list[Any]) -> None:
        """Preflight each model the selected tests will call live, then start the live line."""
        run = self.run
        if not params or run.settings.replays_only:  # nobody called: nothing to check or show
            return
        specs = run.specs_of(params)
        try:
            reports, live = self.preflights.run(specs)
        except (EmrdError, OSError) as exc:  # during collection: end the session in one line
            pytest.exit(failure_line(exc), returncode=pytest.ExitCode.USAGE_ERROR)
        for report in reports:
            for line in report.lines():
                self.write_line(line)
        failed = next((r for r in reports if r.failed), None)
        if failed is not None:
            message = scrub(f"pytest-emrd: {failed.message()}")
            pytest.exit(message, returncode=pytest.ExitCode.USAGE_ERROR)
        if live and self._ticker is None:
            board = LiveBoard(run.session_folder, total=live)
            self._ticker = Ticker(board, self.write_line).start()

    def write_line(self, line: str) -> None:
        """A line on the terminal, also from the live line's thread (capture suspended)."""
        reporter = self.config.pluginmanager.get_plugin("terminalreporter")
        capture = self.config.pluginmanager.get_plugin("capturemanager")
        if reporter is None:
            return
        with capture.global_and_fixture_disabled() if capture else contextlib.nullcontext():
            if getattr(getattr(reporter, "_tw", None), "width_of_current_line", 0):
                reporter.write("\n")  # after a row of progress dots
            reporter.write_line(scrub(line))

    def pytest_runtest_logreport(self, report: pytest.TestReport) -> None:
        if report.when != "call":
            return
        props = dict(report.user_properties)
        if "emrd_verdict" in props:
            self.verdicts.append(Verdict.from_dict(props["emrd_verdict"]))
        if "emrd_episode" not in props:
            return
        summary = EpisodeSummary.from_dict(props["emrd_episode"])
        self.episodes[summary.head.spec.case_id] = summary
        reporter = self.config.pluginmanager.get_plugin("terminalreporter")
        if summary.head.recorded and reporter is not None:
            reporter.ensure_newline()
            reporter.write_line(summary.progress_line(len(self.episodes)))

    def pytest_sessionfinish(self) -> None:
        """Append the run's Markdown to ``$GITHUB_STEP_SUMMARY``, then stop the live line."""
        self._step_summary()
        if self._ticker is not None:
            self._ticker.stop()

    def _step_summary(self) -> None:
        run_dir = self.run.run_dir
        if not os.environ.get("GITHUB_STEP_SUMMARY"):
            return
        if not (self.episodes or self.verdicts) or not (run_dir / "episodes").is_dir():
            return
        from pytest_emrd.report import append_step_summary, registry_prices, step_summary_markdown

        settings = self.run.settings
        source = settings.thresholds
        if source is not None and source.is_relative_to(self.config.rootpath):
            source = source.relative_to(self.config.rootpath)
        try:
            stored = load_run_episodes([run_dir])
            metrics = self.run.store.metrics(stored)  # kept by whoever measured them
        except EmrdError as exc:
            warnings.warn(f"pytest-emrd wrote no step summary: {exc}", stacklevel=1)
            return
        note = None
        if settings.shard and source is not None:
            note = f"A shard: the gates of {source} run over all shards in `emrd gate`."
        append_step_summary(
            step_summary_markdown(
                stored,
                self.verdicts,
                thresholds_source=source and str(source),
                episode_metrics=metrics,
                prices=registry_prices(self.run.registry, {s.head.spec.model for s in stored}),
                gates_note=note,
            )
        )

    def pytest_terminal_summary(self, terminalreporter: Any) -> None:
        from pytest_emrd.report import START_GATES

        if not (self.episodes or self.verdicts):
            return
        tr, run_dir = terminalreporter, self.run.run_dir
        tr.section("EMRD gates" if self.verdicts else "EMRD episodes")
        for line in gate_tables(self.verdicts):
            tr.write_line(line, red=line.lstrip().startswith("FAIL"))
        if self.episodes:
            tr.write_line("tokens per model:")
            for line in usage_table(usage_rows(self.episodes.values())):
                tr.write_line(line)
        if self.run.settings.thresholds is None:
            start = START_GATES.replace("RUN_DIR", str(run_dir))
            tr.write_line(f"no gate ran: no thresholds file. {start}")
        tr.write_line(
            f"results: {run_dir} (resume: --emrd-results {run_dir}; "
            f"gates over shards: emrd gate {run_dir} ...)"
        )
