"""What the run reports at the end (controller, or the only process without xdist): a
progress line per recorded episode, the gate and token tables, ``$GITHUB_STEP_SUMMARY``."""

from __future__ import annotations

import os
import warnings
from typing import Any

import pytest

from pytest_emrd.errors import EmrdError
from pytest_emrd.gate import Verdict
from pytest_emrd.plugin._run import Run
from pytest_emrd.run import EpisodeSummary


class RunReport:
    """Collects the EMRD tests' results (``user_properties``) and prints them."""

    def __init__(self, run: Run) -> None:
        self.run = run
        self.config = run.config
        self.episodes: dict[str, EpisodeSummary] = {}
        self.verdicts: list[Verdict] = []

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
        if (
            summary.head.recorded
            and reporter is not None
            and not hasattr(self.config, "workerinput")
        ):
            reporter.ensure_newline()
            reporter.write_line(summary.progress_line(len(self.episodes)))

    def pytest_sessionfinish(self) -> None:
        """Append the run's Markdown to ``$GITHUB_STEP_SUMMARY`` (controller only)."""
        run_dir = self.run.run_dir
        if not os.environ.get("GITHUB_STEP_SUMMARY") or hasattr(self.config, "workerinput"):
            return
        if not (self.episodes or self.verdicts) or not (run_dir / "episodes").is_dir():
            return
        from pytest_emrd.report import append_step_summary, step_summary_markdown
        from pytest_emrd.run import load_run_episodes, measure_episodes

        source = self.run.settings.thresholds
        if source is not None and source.is_relative_to(self.config.rootpath):
            source = source.relative_to(self.config.rootpath)
        try:
            stored = load_run_episodes([run_dir])
            metrics = measure_episodes(stored)
        except EmrdError as exc:
            warnings.warn(f"pytest-emrd wrote no step summary: {exc}", stacklevel=1)
            return
        append_step_summary(
            step_summary_markdown(
                stored,
                self.verdicts,
                thresholds_source=source and str(source),
                episode_metrics=metrics,
            )
        )

    def pytest_terminal_summary(self, terminalreporter: Any) -> None:
        from pytest_emrd.gate import gate_tables, usage_table
        from pytest_emrd.run import usage_rows

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
        tr.write_line(
            f"results: {run_dir} (resume: --emrd-results {run_dir}; "
            f"gates over shards: emrd gate {run_dir} ...)"
        )
