"""Map rows: no metric depends on the frame the model writes its coordinates in.

Every trajectory is re-expressed in a seeded random proper rigid frame
(:func:`pytest_emrd.metrics.random_reframe`) and every metric computed again; each row reports
the largest change of one metric over all episodes or groups. The paper resolves "arbitrary
egocentric origins" with a rigid Procrustes alignment, so the planted truth is a change of 0.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from typing import Final

import numpy as np

from pytest_emrd.metrics import (
    EpisodeMetrics,
    ebbinghaus,
    episode_metrics,
    miller_curve,
    random_reframe,
)
from pytest_emrd.trajectory import Trajectory
from pytest_emrd.validate._check import Check, Episodes, judged, max_gap

#: A metric may move by at most this much when only the model's frame changes.
FRAME_TOLERANCE: Final = 1e-9
#: Seed of the random frames (one proper rigid motion per episode, drawn in run order).
FRAME_SEED: Final = 20260

Numbers = Callable[[EpisodeMetrics], Sequence[float | None]]

#: Per-episode metric -> the numbers it reports for one episode.
EPISODE_METRICS: Final[dict[str, Numbers]] = {
    "AEC": lambda m: [m.aec],
    "PA": lambda m: [m.pa],
    "TBS(t)": lambda m: m.tbs,
    "SIR": lambda m: [m.sir],
    "time-to-forget (first spells)": lambda m: [s.duration for s in m.ttf_spells],
    "forgetting events": lambda m: [float(s.forgotten) for s in m.ttf_spells],
    "serial position (E/M/L)": lambda m: m.serial_position,
    "memory strength (EFC, per episode)": lambda m: [m.memory_strength],
    "FPSG local / global": lambda m: [m.fpsg_local, m.fpsg_global],
    "Miller load and forgetting": lambda m: [*m.miller_loads, *map(float, m.miller_forgets)],
}


def _pooled(ems: Sequence[EpisodeMetrics]) -> dict[str, list[float | None]]:
    fit = ebbinghaus(ems).pooled
    miller = miller_curve(ems)
    return {
        "Ebbinghaus EFC and R^2 (pooled)": [fit.efc, fit.r2],
        "Miller ML(b) (pooled)": list(miller.probabilities),
    }


def frame_checks(groups: Mapping[str, Episodes]) -> list[Check]:
    """One row per metric: max |change| when every trajectory's maps move to a random frame.

    Only trajectories can be re-expressed; metrics-only episodes are skipped (counted in the
    note). No trajectory at all: no row.

    :param groups: Group name -> its episodes.
    :returns: One :class:`Check` per metric.
    """
    rng = np.random.default_rng(FRAME_SEED)
    worst = dict.fromkeys([*EPISODE_METRICS, *_pooled([])], 0.0)
    n = skipped = 0
    for episodes in groups.values():
        trajs = [e for e in episodes if isinstance(e, Trajectory) and e.status != "errored"]
        skipped += len(episodes) - len(trajs)
        here = [episode_metrics(t) for t in trajs]
        there = [episode_metrics(random_reframe(t, rng)) for t in trajs]
        n += len(trajs)
        for a, b in zip(here, there, strict=True):
            for name, numbers in EPISODE_METRICS.items():
                worst[name] = max(worst[name], max_gap(numbers(a), numbers(b)))
        if trajs:
            before, after = _pooled(here), _pooled(there)
            for name in before:
                worst[name] = max(worst[name], max_gap(before[name], after[name]))
    if not n:
        return []
    note = (
        f"{n} trajectories of {len(groups)} groups, each in its own random proper rigid frame "
        f"(seed {FRAME_SEED})"
        + (f"; {skipped} errored or metrics-only episodes skipped" if skipped else "")
    )
    return [
        Check(
            section="Map",
            name=f"frame invariance: {name}",
            planted="0",
            recovered=f"max |Δ| = {delta:.1e}",
            tolerance=f"<= {FRAME_TOLERANCE:.0e}",
            verdict=judged(delta <= FRAME_TOLERANCE),
            note=note,
            data={"max_abs_delta": delta, "episodes": n},
        )
        for name, delta in worst.items()
    ]
