"""All checks of a validation run, from the trajectories of each planted-agent group."""

from __future__ import annotations

from collections.abc import Mapping, Sequence

from pytest_emrd.errors import ConfigError
from pytest_emrd.metrics import EpisodeMetrics, as_episode_metrics
from pytest_emrd.validate._check import Check, Episode, ValidationReport
from pytest_emrd.validate._decide import prior_checks, scout_decide_checks
from pytest_emrd.validate._explore import exploration_checks
from pytest_emrd.validate._frame import frame_checks
from pytest_emrd.validate._paper import statistics_checks
from pytest_emrd.validate._plan import DECAY_MEANS, GROUPS, WINDOW_SIZES, Group
from pytest_emrd.validate._points import r2_points_checks
from pytest_emrd.validate._remember import (
    decay_checks,
    miller_checks,
    serial_checks,
    window_fit_checks,
)

Groups = Mapping[str, Sequence[Episode]]


def _need(groups: Groups, group: Group) -> list[EpisodeMetrics]:
    """The group's episodes as metrics, matched once and shared by every row."""
    trajs = groups.get(group.name)
    if not trajs:
        raise ConfigError(
            f"group={group.name!r} has no trajectories; run every group of the plan "
            f"({', '.join(g.name for g in GROUPS)})."
        )
    return as_episode_metrics(trajs)


def episode_checks(groups: Groups) -> list[Check]:
    """Every row that needs episodes, in table order (Explore, Remember, Decide)."""
    scout = _need(groups, Group("scout", "baseline"))
    dark = _need(groups, Group("scout", "low_light"))
    decays = {float(m): _need(groups, Group(f"scout-decay-{m}", "baseline")) for m in DECAY_MEANS}
    windows = {k: _need(groups, Group(f"scout-window-{k}", "baseline")) for k in WINDOW_SIZES}
    serial = _need(groups, Group("scout-serial", "baseline"))
    prior = _need(groups, Group("prior", "baseline"))
    return [
        *exploration_checks(scout, dark),
        *frame_checks(groups),
        *decay_checks(decays),
        *window_fit_checks(windows, decays),
        *r2_points_checks(decays, windows, serial),
        *miller_checks(windows, scout),
        *serial_checks(serial, windows, scout),
        *scout_decide_checks(scout),
        *prior_checks(prior),
    ]


def validation_report(groups: Groups, *, episodes: int, protocol: str) -> ValidationReport:
    """Episode checks followed by the statistics rows."""
    return ValidationReport((*episode_checks(groups), *statistics_checks()), episodes, protocol)
