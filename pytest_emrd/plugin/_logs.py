"""Scrubbed logs: pytest's log handlers and the HTTP libraries' loggers get the scrub filter.

pytest installs its live-log (``--log-cli-level``), log-file and capture handlers on the
root logger only while a phase runs, so the filter is attached at the start of the session
and of each test, when they are installed (:func:`pytest_emrd._scrub.install_log_scrub`).
"""

from __future__ import annotations

import pytest

from pytest_emrd._scrub import install_log_scrub, remove_log_scrub


class LogScrub:
    """Attaches the scrub filter whenever pytest's log handlers are installed."""

    @pytest.hookimpl(tryfirst=True)
    def pytest_sessionstart(self) -> None:
        install_log_scrub()

    @pytest.hookimpl(tryfirst=True)
    def pytest_collection(self) -> None:
        install_log_scrub()

    @pytest.hookimpl(tryfirst=True)
    def pytest_runtest_setup(self) -> None:
        install_log_scrub()

    def pytest_unconfigure(self) -> None:
        remove_log_scrub()
