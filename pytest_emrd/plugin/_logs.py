"""Scrubbed logs: pytest installs its log handlers on the root logger only while a phase runs,
so the scrub filter (:func:`pytest_emrd._scrub.install_log_scrub`) is attached at the start
of the session, of collection and of each test."""

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
