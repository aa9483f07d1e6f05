"""Collection: EMRD tests parametrised over the run's episodes and gates; empty grids and
missing cassettes handled once; secrets kept out of EMRD test reports."""

from __future__ import annotations

from typing import Any

import pytest

from pytest_emrd._scrub import scrub_report
from pytest_emrd.gate import GateCell
from pytest_emrd.plugin._run import RUN
from pytest_emrd.trajectory import EpisodeSpec


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
    """Drop the placeholder items of an empty grid (a shard's gates, a model without gates);
    stop a replay-only run with missing cassettes with one summary (after ``-k``)."""
    empty = [item for item in items if _is_empty_emrd_item(item)]
    if empty:
        config.hook.pytest_deselected(items=empty)
        items[:] = [item for item in items if item not in empty]
    run = config.stash.get(RUN, None)
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
