"""Metric validity: reference agents with planted cognition in, the same numbers out.

Each check is a row (planted value, recovered value, tolerance, verdict, note) computed by
pure functions over trajectories with :mod:`pytest_emrd.metrics`; :func:`run_plan` runs and
caches the episodes; ``emrd validate`` prints and writes the table.
"""

from pytest_emrd.validate._check import VERDICTS, Check, ValidationReport
from pytest_emrd.validate._decide import prior_checks, scout_decide_checks
from pytest_emrd.validate._explore import exploration_checks
from pytest_emrd.validate._frame import FRAME_SEED, FRAME_TOLERANCE, frame_checks
from pytest_emrd.validate._paper import statistics_checks
from pytest_emrd.validate._plan import (
    DECAY_MEANS,
    FAMILIES,
    FULL_EPISODES,
    GROUPS,
    MIMIC_MODELS,
    WINDOW_SIZES,
    Group,
    Plan,
)
from pytest_emrd.validate._points import r2_points_checks
from pytest_emrd.validate._remember import (
    decay_checks,
    episodes_needed,
    error_curve,
    miller_checks,
    monotone,
    serial_checks,
    u_depth,
    window_fit_checks,
)
from pytest_emrd.validate._render import markdown, to_json
from pytest_emrd.validate._run import Progress, run_plan
from pytest_emrd.validate._suite import episode_checks, validation_report

__all__ = [
    "DECAY_MEANS",
    "FAMILIES",
    "FRAME_SEED",
    "FRAME_TOLERANCE",
    "FULL_EPISODES",
    "GROUPS",
    "MIMIC_MODELS",
    "VERDICTS",
    "WINDOW_SIZES",
    "Check",
    "Group",
    "Plan",
    "Progress",
    "ValidationReport",
    "decay_checks",
    "episode_checks",
    "episodes_needed",
    "error_curve",
    "exploration_checks",
    "frame_checks",
    "markdown",
    "miller_checks",
    "monotone",
    "prior_checks",
    "r2_points_checks",
    "run_plan",
    "scout_decide_checks",
    "serial_checks",
    "statistics_checks",
    "to_json",
    "u_depth",
    "validation_report",
    "window_fit_checks",
]
