"""Preflight and the live progress line (controller only: the only process, or xdist's): each
model the selected tests will call live is preflighted once, and a failure ends the session
before any episode runs; then a ticker prints the live line from the workers' status files."""

from __future__ import annotations

import contextlib
from functools import cached_property
from typing import Any

import pytest

from pytest_emrd._scrub import scrub
from pytest_emrd.errors import EmrdError
from pytest_emrd.gate import GateCell
from pytest_emrd.plugin._run import Run, failure_line


class LiveLine:
    """The controller's preflight and live line for one :class:`Run`."""

    def __init__(self, run: Run) -> None:
        self.run = run
        self.config = run.config
        self._ticker: Any = None

    def pytest_collection_finish(self, session: pytest.Session) -> None:
        if hasattr(self.config, "workerinput") or self.config.option.collectonly:
            return
        names = ("emrd_spec", "emrd_gate")
        params = [getattr(i, "callspec", None) for i in session.items]
        self.preflight([c.params[n] for c in params if c for n in names if n in c.params])

    @pytest.hookimpl(optionalhook=True)
    def pytest_xdist_node_collection_finished(self, node: Any, ids: list[str]) -> None:
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
        """Preflight each model the selected tests will call live; a failure ends the session
        before any episode runs. Then start the live line."""
        run = self.run
        if not params or run.settings.replays_only:  # nobody called: nothing to check or show
            return
        from pytest_emrd.progress import LiveBoard, Ticker

        cells = (run.cell_specs(p) if isinstance(p, GateCell) else [p] for p in params)
        specs = [spec for group in cells for spec in group]
        try:
            reports, live = self.preflights.run(specs)
        except (EmrdError, OSError) as exc:  # during collection: end the session in one line
            pytest.exit(failure_line(exc), returncode=pytest.ExitCode.USAGE_ERROR)
        for line in (line for report in reports for line in report.lines()):
            self.write_line(line)
        failed = next((r for r in reports if r.failed), None)
        if failed is not None:
            message = scrub(f"pytest-emrd: {failed.message()}")
            pytest.exit(message, returncode=pytest.ExitCode.USAGE_ERROR)
        if live and self._ticker is None:
            board = LiveBoard(run.session_folder, total=live)
            self._ticker = Ticker(board, self.write_line).start()

    def write_line(self, line: str) -> None:
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

    def pytest_sessionfinish(self) -> None:
        """Stop the live line."""
        if self._ticker is not None:
            self._ticker.stop()
            self._ticker = None
