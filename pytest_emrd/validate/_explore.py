"""Explore and Decide rows.

Explore: the scout's coverage is what it was shown, and low light costs coverage and time
for the same agent in the same offices (paired episodes). The scout has perfect memory and
maps all it sees, so its planted coverage is ``|union_t V_t| / |E|`` (``V_t`` the step's
ground-truth visible ids): what Eq. AEC must recover, per episode, exactly. ``|G_base| / |E|``
(visible from *some* standing point) measures the office, not the tour: furniture occludes
and objects count as visible within 3.3 m, so a 50-step scout leaves parts of the open-plan
Office unseen (about 5 % of ``E``), which no metric can recover; the row reports it beside.

Decide: Never-Visited, Any-Bias and FPSG recover the planted grounding of ``prior`` (a
textual prior, no evidence) and ``scout`` (chooses where it mapped the most).
"""

from __future__ import annotations

import math
import statistics
from collections.abc import Sequence
from typing import Final

from pytest_emrd.metrics import GATE_METRICS, Estimate, FPSGSummary, as_episode_metrics, fpsg
from pytest_emrd.trajectory import Trajectory
from pytest_emrd.validate._check import Check, Episodes, fmt, judged, pct

#: Per episode, the scout's AEC may differ from the fraction it was shown by at most this
#: (numbers agree to 1e-9 across CPUs).
COVERAGE_TOL: Final = 1e-9


def _value(estimate: Estimate) -> float:
    return estimate.value if estimate.value is not None else math.nan


def _ci(estimate: Estimate) -> str:
    return f"95 % CI {fmt(estimate.ci_low, 3)}-{fmt(estimate.ci_high, 3)}"


def shown_fraction(traj: Trajectory) -> float | None:
    """``|union_t V_t ∩ E| / |E|``: the share of the ground-truth objects in view at some
    step of ``traj`` (what a perfect-memory agent that maps all it sees covers). None when
    the ground truth lists no object."""
    ids = {o.object_id for o in traj.ground_truth.objects}
    seen = {i for step in traj.steps for i in step.visible_ids}
    return len(seen & ids) / len(ids) if ids else None


def _mean(values: Sequence[float]) -> float:
    return statistics.fmean(values) if values else math.nan


def exploration_checks(baseline: Sequence[Trajectory], low_light: Episodes) -> list[Check]:
    """Scout AEC equals the fraction it was shown, per episode; low_light lowers AEC and
    raises TE. ``baseline`` must be trajectories (the first row reads the visible ids).

    :param baseline: The scout's baseline trajectories.
    :param low_light: Its ``low_light`` episodes.
    :returns: The Explore :class:`Check` rows.
    """
    aec, te = GATE_METRICS["aec"], GATE_METRICS["te"]
    metrics = as_episode_metrics(baseline)
    base_aec, dark_aec = aec.compute(metrics), aec.compute(low_light)
    base_te, dark_te = te.compute(metrics), te.compute(low_light)
    pairs = [
        (m.aec, shown, m.g_base / len(t.ground_truth.objects))
        for t, m in zip(baseline, metrics, strict=True)
        if m.aec is not None and (shown := shown_fraction(t)) is not None
    ]
    planted = _mean([s for _, s, _ in pairs])
    discoverable = _mean([g for _, _, g in pairs])
    worst = max((abs(a - s) for a, s, _ in pairs), default=math.nan)
    return [
        Check(
            section="Explore",
            name="AEC vs fraction shown, scout",
            planted=fmt(planted, 3),
            recovered=f"{fmt(base_aec.value, 3)}; max |diff| {worst:.1e}",
            tolerance=f"exactly, per episode (<= {COVERAGE_TOL:g})",
            verdict=judged(worst <= COVERAGE_TOL),
            note=f"{len(pairs)} episodes; shown = |union_t V_t|/|E| (ids in view at some step); "
            f"mean |G_base|/|E| {fmt(discoverable, 3)} (the rest of G_base was never in "
            f"view); {_ci(base_aec)}",
            data={
                "aec": base_aec.value,
                "shown": planted,
                "max_diff": worst,
                "discoverable": discoverable,
            },
        ),
        Check(
            section="Explore",
            name="AEC, scout: low_light vs baseline",
            planted="lower",
            recovered=f"{fmt(dark_aec.value, 3)} vs {fmt(base_aec.value, 3)}",
            tolerance="strictly lower",
            verdict=judged(_value(dark_aec) < _value(base_aec)),
            note=f"{dark_aec.n} paired episodes; low_light {_ci(dark_aec)}",
            data={"aec_low_light": dark_aec.value, "aec_baseline": base_aec.value},
        ),
        Check(
            section="Explore",
            name="TE, scout: low_light vs baseline",
            planted="higher",
            recovered=f"{fmt(dark_te.value, 1)} vs {fmt(base_te.value, 1)} steps",
            tolerance="strictly higher",
            verdict=judged(_value(dark_te) > _value(base_te)),
            note=f"{dark_te.n} paired episodes; low_light {_ci(dark_te)}",
            data={"te_low_light": dark_te.value, "te_baseline": base_te.value},
        ),
    ]


#: ``FPSG_local`` of the perfect-memory scout's chosen room must be at least this.
SCOUT_MIN_LOCAL: Final = 0.9


def _share(name: str, agent: str, s: FPSGSummary, planted: float) -> Check:
    """``agent``'s share ``name`` (``Never-Visited``, ``Any-Bias``: a field of ``s``) is
    exactly ``planted``."""
    field = name.lower().replace("-", "_")
    share, want = getattr(s, field), f"{100 * planted:g} %"
    return Check(
        section="Decide",
        name=f"{name}, {agent}",
        planted=want,
        recovered=pct(share),
        tolerance=f"exactly {want}",
        verdict=judged(share == planted),
        note=f"{s.runs} episodes",
        data={field: share},
    )


def prior_checks(trajectories: Episodes) -> list[Check]:
    """``prior`` names a room it never entered, from the prompt alone: Never-Visited and
    Any-Bias 100 %, FPSG 0.

    :param trajectories: The ``prior`` agent's episodes.
    :returns: The Decide rows of ``prior``.
    """
    s = fpsg(trajectories)
    return [
        _share("Never-Visited", "prior", s, 1.0),
        _share("Any-Bias", "prior", s, 1.0),
        Check(
            section="Decide",
            name="FPSG global, prior",
            planted="0",
            recovered=fmt(s.global_mean, 3),
            tolerance="exactly 0",
            verdict=judged(s.global_mean == 0.0),
            note=f"{s.runs} episodes; local {fmt(s.local_mean, 3)}",
            data={"fpsg_global": s.global_mean, "fpsg_local": s.local_mean},
        ),
    ]


def scout_decide_checks(trajectories: Episodes) -> list[Check]:
    """``scout`` chooses a room it swept and remembers: Never-Visited 0 %, FPSG local ~ 1.

    :param trajectories: The ``scout`` agent's episodes.
    :returns: The Decide rows of ``scout``.
    """
    s = fpsg(trajectories)
    return [
        _share("Never-Visited", "scout", s, 0.0),
        Check(
            section="Decide",
            name="FPSG local, scout",
            planted="1 (near)",
            recovered=fmt(s.local_mean, 3),
            tolerance=f">= {SCOUT_MIN_LOCAL}",
            verdict=judged(s.local_mean is not None and s.local_mean >= SCOUT_MIN_LOCAL),
            note=f"{s.runs} episodes; sd {fmt(s.local_sd, 3)}, global {fmt(s.global_mean, 3)}",
            data={"fpsg_local": s.local_mean, "fpsg_global": s.global_mean},
        ),
    ]
