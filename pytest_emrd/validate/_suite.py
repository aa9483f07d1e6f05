"""All checks of a validation run, from the trajectories of each planted-agent group."""

from __future__ import annotations

from collections.abc import Mapping, Sequence

from pytest_emrd.agent import load_registry
from pytest_emrd.errors import ConfigError
from pytest_emrd.metrics import EpisodeMetrics, as_episode_metrics
from pytest_emrd.trajectory import Trajectory
from pytest_emrd.validate._check import Check, Episode, ValidationReport
from pytest_emrd.validate._explore import exploration_checks, prior_checks, scout_decide_checks
from pytest_emrd.validate._frame import frame_checks
from pytest_emrd.validate._mimic import (
    dup_checks,
    halluc_checks,
    own_frame_checks,
    paired,
    reply_checks,
    sigma_check,
)
from pytest_emrd.validate._paper import statistics_checks
from pytest_emrd.validate._plan import (
    DECAY_MEANS,
    GROUPS,
    MIMIC_DUP,
    MIMIC_GROUPS,
    MIMIC_HALLUC,
    MIMIC_MODELS,
    MIMIC_SIGMA,
    WINDOW_SIZES,
)
from pytest_emrd.validate._remember import (
    decay_checks,
    miller_checks,
    r2_points_checks,
    serial_checks,
    window_fit_checks,
)

Groups = Mapping[str, Sequence[Episode]]


def _episodes(groups: Groups, name: str) -> Sequence[Episode]:
    trajs = groups.get(name)
    if not trajs:
        raise ConfigError(
            f"group={name!r} has no trajectories; run every group of the plan "
            f"({', '.join(g.name for g in GROUPS)})."
        )
    return trajs


def _need(groups: Groups, name: str) -> list[EpisodeMetrics]:
    """The episodes of group ``name`` as metrics, matched once and shared by every row."""
    return as_episode_metrics(_episodes(groups, name))


def _trajectories(groups: Groups, name: str) -> list[Trajectory]:
    trajs = _episodes(groups, name)
    if not all(isinstance(t, Trajectory) for t in trajs):
        raise ConfigError(f"group={name!r} needs trajectories (its rows read the raw replies).")
    return [t for t in trajs if isinstance(t, Trajectory)]


def mimic_checks(groups: Groups) -> list[Check]:
    """Frame, noise, hallucination, duplicate and reply rows of the mimic groups."""
    role = {
        r: _trajectories(groups, next(g.name for g in MIMIC_GROUPS if g.model == m))
        for r, m in MIMIC_MODELS.items()
    }
    clean = paired(role["own"])
    return [
        *own_frame_checks(paired(role["spawn"]), clean),
        sigma_check(paired(role["sigma"]), clean, MIMIC_SIGMA),
        *halluc_checks(paired(role["halluc"]), clean, MIMIC_HALLUC),
        *dup_checks(paired(role["dup"]), clean, MIMIC_DUP),
        *reply_checks(role["default"], role["own"], load_registry().get("mimic").planted),
    ]


def episode_checks(groups: Groups) -> list[Check]:
    """Every row whose groups were run, in table order: the scout family's rows (Explore,
    Remember, Decide), then the mimic family's (Map, Explore, Remember, Replies)."""
    rows = scout_checks(groups) if "scout" in groups else []
    return rows + (mimic_checks(groups) if "mimic" in groups else [])


def scout_checks(groups: Groups) -> list[Check]:
    """Rows of the scout family (and ``prior``)."""
    scout, dark = _need(groups, "scout"), _need(groups, "scout@low_light")
    decays = {float(m): _need(groups, f"scout-decay-{m}") for m in DECAY_MEANS}
    windows = {k: _need(groups, f"scout-window-{k}") for k in WINDOW_SIZES}
    serial, prior = _need(groups, "scout-serial"), _need(groups, "prior")
    return [
        *exploration_checks(_trajectories(groups, "scout"), dark),
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
