"""Metric validity: reference agents with planted cognition in, the same numbers out.

Each check is a row (planted, recovered, tolerance, verdict, note) computed by pure functions
over trajectories; :func:`run_plan` runs and caches the episodes. Names are imported on first
use (:mod:`pytest_emrd._lazy`), so ``emrd --help`` reads the plan without the metrics.
"""

from pytest_emrd._lazy import lazy_exports

__getattr__, __dir__, __all__ = lazy_exports(
    __name__,
    {
        "_check": ("VERDICTS", "Check", "ValidationReport", "markdown", "to_json"),
        "_explore": ("exploration_checks", "prior_checks", "scout_decide_checks"),
        "_frame": ("FRAME_SEED", "FRAME_TOLERANCE", "frame_checks"),
        "_paper": ("statistics_checks",),
        "_plan": (
            "DECAY_MEANS",
            "FAMILIES",
            "FULL_EPISODES",
            "GROUPS",
            "MIMIC_MODELS",
            "WINDOW_SIZES",
            "Group",
            "Plan",
        ),
        "_remember": (
            "decay_checks",
            "episodes_needed",
            "error_curve",
            "miller_checks",
            "monotone",
            "r2_points_checks",
            "serial_checks",
            "u_depth",
            "window_fit_checks",
        ),
        "_run": ("Progress", "run_plan"),
        "_suite": ("episode_checks", "validation_report"),
    },
)
