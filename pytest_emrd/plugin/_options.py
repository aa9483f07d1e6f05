"""The ``--emrd-*`` options and their ini twins; the run's settings, resolved once per process.

The controller (or the only process) picks the run directory and the session id; xdist
workers receive both through ``workerinput``.
"""

from __future__ import annotations

import uuid
import warnings
from pathlib import Path
from typing import Any

import pytest

from pytest_emrd._scrub import scrub
from pytest_emrd.errors import EmrdError
from pytest_emrd.plugin._live import LiveLine
from pytest_emrd.plugin._logs import LogScrub
from pytest_emrd.plugin._report import RunReport
from pytest_emrd.plugin._run import RUN, Run
from pytest_emrd.run import OPTIONS, check_resume, new_run_dir, resolve_settings


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
    run = Run(config, settings, run_dir, session)
    config.stash[RUN] = run
    config.pluginmanager.register(run, "emrd-run")
    config.pluginmanager.register(LiveLine(run), "emrd-live")
    config.pluginmanager.register(RunReport(run), "emrd-report")
    config.pluginmanager.register(LogScrub(), "emrd-log-scrub")
    if workerinput is None:  # the controller names a stopped model's endpoint once, at the end
        config.pluginmanager.register(run.endpoints, "emrd-endpoints")


@pytest.hookimpl(optionalhook=True)
def pytest_configure_node(node: Any) -> None:
    """pytest-xdist: every worker shares the controller's run directory and session."""
    run = node.config.stash[RUN]
    node.workerinput["emrd_run_dir"] = str(run.run_dir)
    node.workerinput["emrd_session"] = run.session
