"""All checks of a validation run, from the trajectories of each planted-agent group."""

from __future__ import annotations

from collections.abc import Mapping

from pytest_emrd.agent import load_registry
from pytest_emrd.errors import ConfigError
from pytest_emrd.metrics import EpisodeMetrics, as_episode_metrics
from pytest_emrd.trajectory import Trajectory
from pytest_emrd.validate import _mimic, _plan, _remember
from pytest_emrd.validate._check import Check, Episodes, ValidationReport
from pytest_emrd.validate._explore import exploration_checks, prior_checks, scout_decide_checks
from pytest_emrd.validate._frame import frame_checks
from pytest_emrd.validate._paper import statistics_checks

Groups = Mapping[str, Episodes]


def _episodes(groups: Groups, name: str) -> Episodes:
    trajs = groups.get(name)
    if not trajs:
        raise ConfigError(
            f"group={name!r} has no trajectories; run every group of the plan "
            f"({', '.join(g.name for g in _plan.GROUPS)})."
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
    role = {  # MIMIC_GROUPS lists the models of MIMIC_MODELS in its order
        r: _trajectories(groups, g.name)
        for r, g in zip(_plan.MIMIC_MODELS, _plan.MIMIC_GROUPS, strict=True)
    }
    clean = _mimic.paired(role["own"])
    return [
        *_mimic.own_frame_checks(_mimic.paired(role["spawn"]), clean),
        _mimic.sigma_check(_mimic.paired(role["sigma"]), clean, _plan.MIMIC_SIGMA),
        *_mimic.halluc_checks(_mimic.paired(role["halluc"]), clean, _plan.MIMIC_HALLUC),
        *_mimic.dup_checks(_mimic.paired(role["dup"]), clean, _plan.MIMIC_DUP),
        *_mimic.reply_checks(role["default"], role["own"], load_registry().get("mimic").planted),
    ]


def episode_checks(groups: Groups) -> list[Check]:
    """Every row whose groups were run, in table order: the scout family's rows (Explore,
    Remember, Decide), then the mimic family's (Map, Explore, Remember, Replies).

    :param groups: Group name -> its episodes.
    :returns: The :class:`Check` rows.
    """
    rows = scout_checks(groups) if "scout" in groups else []
    return rows + (mimic_checks(groups) if "mimic" in groups else [])


def scout_checks(groups: Groups) -> list[Check]:
    """Rows of the scout family (and ``prior``)."""
    scout, dark = _need(groups, "scout"), _need(groups, "scout@low_light")
    decays = {float(m): _need(groups, f"scout-decay-{m}") for m in _plan.DECAY_MEANS}
    windows = {k: _need(groups, f"scout-window-{k}") for k in _plan.WINDOW_SIZES}
    serial, prior = _need(groups, "scout-serial"), _need(groups, "prior")
    return [
        *exploration_checks(_trajectories(groups, "scout"), dark),
        *frame_checks(groups),
        *_remember.decay_checks(decays),
        *_remember.window_fit_checks(windows, decays),
        *_remember.r2_points_checks(decays, windows, serial),
        *_remember.miller_checks(windows, scout),
        *_remember.serial_checks(serial, windows, scout),
        *scout_decide_checks(scout),
        *prior_checks(prior),
    ]


def validation_report(groups: Groups, *, episodes: int, protocol: str) -> ValidationReport:
    """Episode checks followed by the statistics rows.

    :param groups: Group name -> its episodes.
    :param episodes: Episodes per group, as planned.
    :param protocol: The protocol version the episodes ran under.
    :returns: The :class:`ValidationReport`.
    """
    return ValidationReport((*episode_checks(groups), *statistics_checks()), episodes, protocol)
