"""Map, Explore, Remember and reply rows for the ``mimic`` family: the metrics recover what a
VLM-like writer plants (:mod:`pytest_emrd.reference._mimic`).

Every group walks the same paths (the knobs do not touch navigation; damaged replies and
invalid actions are off except in the default group), so groups are compared episode by
episode; the planted truth is read from the agent's own state, which travels in its replies.

* **Frame.** Both frames write coordinates to 0.01 m, so the own-frame map is a rigid image
  of the spawn-frame map up to ``delta <= sqrt(2) * 0.01`` m per point. The optimal
  Procrustes residual is 1-Lipschitz in the points (RMS norm), so ``|PA_own - PA_spawn| <=
  delta / L_gt`` per episode (coverage unchanged); AEC and SIR (counts) are equal exactly.
* **Noise.** With ``n`` matched pairs, i.i.d. N(0, sigma^2) noise per coordinate and a proper
  rigid fit (3 parameters), ``E[SSR] = SSR_0 + sigma^2 (2n - 3)`` (``SSR = n RMSE^2``,
  ``SSR_0`` of the paired noise-free episode). PA gives ``RMSE = -L_gt ln(PA / c)`` (``c`` its
  coverage factor), so ``sigma_hat^2 = sum_i (SSR_i - SSR_0,i) / sum_i (2 n_i - 3)``, with a
  bootstrap CI over episodes.
* **Hallucinations** name no type of the layout, so AEC, PA and SIR equal the clean
  episode's exactly, and the unrecognised entries of the terminal map are Binomial(T, h):
  ``h_hat = sum unrecognised / sum T`` with a Clopper-Pearson interval.
* **Duplicates.** Eq. AEC per episode: ``AEC_p = sum_k min(|M_k| + D_k, |E_k|) / |E|`` with
  ``|M_k|`` the clean map's entries of type ``k`` and ``D_k`` the planted duplicates: AEC can
  only rise, and only where type ``k`` still has unmapped instances. SIR (Appendix B: objects
  of ``M_first`` "recognised and successfully deduplicated" on re-entry): an object that got
  a duplicate during the re-entry was not deduplicated, so the per-room ratio falls to the
  share of ``M_first`` without a duplicate at the re-entry's end.
* **Replies.** Parse failures over all steps recover ``fail``; replies read with a repair
  over readable replies recover ``repair``; refused actions over readable replies, net of
  the clean mimic's own refusal rate ``f_0``, recover ``invalid`` (``(f - f_0) / (1 - f_0)``).
"""

from __future__ import annotations

import math
from collections import Counter
from collections.abc import Mapping, Sequence
from typing import Final

import numpy as np
from statsmodels.stats.proportion import proportion_confint

from pytest_emrd.metrics import (
    EpisodeMetrics,
    bootstrap_ci,
    episode_metrics,
    layout_scale,
    match_map,
    pa_coverage,
    track_episode,
)
from pytest_emrd.reference import read_state
from pytest_emrd.trajectory import Trajectory
from pytest_emrd.validate._check import Check, fmt, judged, max_gap, pct

#: Coordinates are written to this many metres in every frame.
WRITTEN_M: Final = 0.01
#: Relative error allowed on the recovered sigma.
SIGMA_TOLERANCE: Final = 0.1
#: Exact equalities are checked to this (floating-point summation only).
EXACT: Final = 1e-12

Paired = Sequence[tuple[Trajectory, EpisodeMetrics]]


def paired(trajectories: Sequence[Trajectory]) -> list[tuple[Trajectory, EpisodeMetrics]]:
    """Each trajectory with its metrics (computed once)."""
    return [(t, episode_metrics(t)) for t in trajectories]


def _planted_ids(traj: Trajectory, step: int) -> dict[str, str]:
    """Label -> planted object id in the agent's state after step index ``step``."""
    entries = read_state(traj.steps[step].raw_reply)["map"]
    return {label: rec["id"] for label, rec in entries.items() if "id" in rec}


def rmse_from_pa(
    pa: float | None, matched: int, g_base: int, truth: np.ndarray, unmatched: int = 0
) -> float:
    r"""The RMSE inside Eq. PA, read back from the score.

    .. math::
        PA = \exp(-RMSE / L_{gt}) \cdot c \;\Rightarrow\; RMSE = -L_{gt} \ln(PA / c)

    ``c`` is PA's coverage factor with its charge for ``unmatched`` entries
    (:func:`~pytest_emrd.metrics.pa_coverage`).
    ``truth`` are the matched ground-truth points (``L_gt`` is their RMS spread). NaN when it
    cannot be read back: PA undefined or 0, ``|G_base| = 0``, or fewer than two points
    (``L_gt = 0``).
    """
    scale = layout_scale(np.asarray(truth, dtype=float).reshape(-1, 2))
    coverage = pa_coverage(matched, unmatched, g_base)
    if pa is None or pa <= 0.0 or coverage == 0.0 or scale == 0.0:
        return math.nan
    return -scale * math.log(min(1.0, pa / coverage))


def sigma_estimate(rows: np.ndarray) -> float:
    r"""Pooled noise sigma from paired residuals: rows ``(SSR_i - SSR_0,i, 2 n_i - 3)``.

    .. math::
        \hat\sigma^2 = \frac{\sum_i (SSR_i - SSR_{0,i})}{\sum_i (2 n_i - 3)}

    (``E[SSR] = SSR_0 + sigma^2 (2n - 3)`` for i.i.d. N(0, sigma^2) noise per coordinate after a
    fitted rotation + translation). A negative pooled excess gives 0; no rows give NaN.
    """
    rows = np.asarray(rows, dtype=float).reshape(-1, 2)
    if not len(rows) or rows[:, 1].sum() <= 0:
        return math.nan
    return math.sqrt(max(0.0, rows[:, 0].sum() / rows[:, 1].sum()))


def _rmse(traj: Trajectory, m: EpisodeMetrics) -> tuple[int, float, float]:
    """``(n, RMSE, L_gt)`` of the terminal map, RMSE read back from PA."""
    truth = np.array(
        [(p.true_x, p.true_z) for p in match_map(traj.final_map, traj.ground_truth.objects).pairs]
    ).reshape(-1, 2)
    rmse = rmse_from_pa(m.pa, m.matched, m.g_base, truth, m.unmatched)
    return m.matched, rmse, layout_scale(truth)


def _gaps(a: Paired, b: Paired, *names: str) -> dict[str, float]:
    """The :func:`max_gap` of each metric in ``names`` between paired episodes."""
    return {n: max_gap([getattr(m, n) for _, m in a], [getattr(m, n) for _, m in b]) for n in names}


def own_frame_checks(spawn: Paired, own: Paired) -> list[Check]:
    """PA within the rounding bound, AEC and SIR exactly, own frame vs spawn frame."""
    excess = []
    for (traj, s), (_, o) in zip(spawn, own, strict=True):
        _, _, scale = _rmse(traj, s)
        bound = math.sqrt(2.0) * WRITTEN_M / scale if scale else 0.0
        excess.append(abs((o.pa or 0.0) - (s.pa or 0.0)) - bound)
    pa_gap, aec_gap, sir_gap, k_gap = _gaps(own, spawn, "pa", "aec", "sir", "matched").values()
    same = k_gap == 0
    note = f"{len(own)} paired episodes; the own frame is a seeded rotation + translation"
    return [
        Check(
            section="Map",
            name="PA, mimic: own frame vs spawn frame",
            planted="equal",
            recovered=f"max |diff| {fmt(pa_gap, 4)}",
            tolerance="rounding: sqrt(2) * 0.01 m / L_gt per episode",
            verdict=judged(same and max(excess, default=0.0) <= EXACT),
            note=f"{note}; same |K| in every episode: {same}",
            data={"max_pa_gap": pa_gap, "max_excess_over_bound": max(excess, default=0.0)},
        ),
        Check(
            section="Map",
            name="AEC and SIR, mimic: own frame vs spawn frame",
            planted="equal",
            recovered=f"max |diff| {fmt(aec_gap, 4)} / {fmt(sir_gap, 4)}",
            tolerance="exactly",
            verdict=judged(aec_gap <= EXACT and sir_gap <= EXACT),
            note=note,
            data={"max_aec_gap": aec_gap, "max_sir_gap": sir_gap},
        ),
    ]


def sigma_check(noisy: Paired, clean: Paired, sigma: float) -> Check:
    """sigma recovered from PA's RMSE against the paired noise-free episodes."""
    rows = []
    for (tn, mn), (tc, mc) in zip(noisy, clean, strict=True):
        n, rmse, _ = _rmse(tn, mn)
        n0, rmse0, _ = _rmse(tc, mc)
        if n == n0 and n >= 3 and math.isfinite(rmse) and math.isfinite(rmse0):
            rows.append((n * rmse**2 - n0 * rmse0**2, 2.0 * n - 3.0))
    data = np.array(rows).reshape(-1, 2)
    estimate = sigma_estimate(data)
    low, high = bootstrap_ci(
        data, lambda a: np.sqrt(np.clip(a[..., 0].sum(axis=1) / a[..., 1].sum(axis=1), 0, None))
    )
    error = abs(estimate - sigma) / sigma
    return Check(
        section="Map",
        name=f"Position noise sigma from PA's RMSE, mimic-s{sigma:g}",
        planted=f"{sigma:g} m",
        recovered=f"{fmt(estimate, 3)} m",
        tolerance=f"within {SIGMA_TOLERANCE:.0%}",
        verdict=judged(error <= SIGMA_TOLERANCE),
        note=f"{len(data)} paired episodes; sigma_hat^2 = sum(SSR - SSR_0) / sum(2n - 3), "
        "RMSE = -L_gt ln(PA / coverage); bootstrap 95 % CI "
        f"{fmt(low, 3)}-{fmt(high, 3)}",
        data={"sigma": sigma, "sigma_hat": estimate, "ci_low": low, "ci_high": high},
    )


def rate_check(section: str, name: str, planted: float, count: int, total: int, note: str) -> Check:
    low, high = proportion_confint(count, total, alpha=0.05, method="beta") if total else (0, 1)
    return Check(
        section=section,
        name=name,
        planted=pct(planted),
        recovered=pct(count / total if total else None),
        tolerance="planted value inside the 95 % Clopper-Pearson interval",
        verdict=judged(low <= planted <= high),
        note=f"{count} of {total}; CI {pct(low)}-{pct(high)}; {note}",
        data={"planted": planted, "count": count, "total": total, "ci_low": low, "ci_high": high},
    )


def halluc_checks(halluc: Paired, clean: Paired, h: float) -> list[Check]:
    """Hallucinations change no score and are counted as unrecognised, Binomial(T, h)."""
    gaps = _gaps(halluc, clean, "aec", "pa", "sir")

    def unrecognised(t: Trajectory) -> int:
        return len(match_map(t.final_map, t.ground_truth.objects).unrecognised)

    count = sum(
        unrecognised(th) - unrecognised(tc) for (th, _), (tc, _) in zip(halluc, clean, strict=True)
    )
    total = sum(len(t.steps) for t, _ in halluc)
    return [
        Check(
            section="Explore",
            name=f"AEC, PA, SIR with hallucinations, mimic-h{h:g}",
            planted="unchanged",
            recovered=" / ".join(f"{fmt(v, 4)}" for v in gaps.values()) + " max |diff|",
            tolerance="exactly",
            verdict=judged(all(v <= EXACT for v in gaps.values())),
            note=f"{len(halluc)} paired episodes; Eq. AEC's min cap: unrecognised entries count "
            "for nothing",
            data={f"max_{k}_gap": v for k, v in gaps.items()},
        ),
        rate_check(
            "Explore",
            f"Hallucinated entries per step, mimic-h{h:g}",
            h,
            count,
            total,
            "unrecognised entries of the terminal map over steps",
        ),
    ]


def _copied_during(traj: Trajectory, start: int, end: int) -> set[str]:
    """Objects the agent wrote a copy of between step indices ``start`` and ``end``: two or more
    labels after ``end``, one of them new since before ``start`` (as SIR's copies are new
    entries), so an object duplicated before the re-entry and copied again during it counts."""
    before = set(_planted_ids(traj, start - 1)) if start > 0 else set()
    after = _planted_ids(traj, end)
    labels = Counter(after.values())
    return {o for label, o in after.items() if labels[o] > 1 and label not in before}


def _sir_ratio_planted(traj: Trajectory) -> float | None:
    """Mean over re-entered rooms of the share of ``M_first`` without a duplicate (paper)."""
    track = track_episode(traj)
    room_of = {o.object_id: o.room for o in traj.ground_truth.objects}
    ratios = []
    for v in track.visits:
        if v.return_end is None or v.return_start is None:
            continue
        first = {o for o in track.held[v.first_end] if room_of[o] == v.room}
        if first:
            dup = _copied_during(traj, v.return_start, v.return_end)
            ratios.append(len(first - dup) / len(first))
    return float(np.mean(ratios)) if ratios else None


def dup_checks(dup: Paired, clean: Paired, p: float) -> list[Check]:
    """Eq. AEC with the planted duplicates; SIR's ratio against the planted duplicates."""
    predicted, recovered, rises = [], [], []
    for (td, md), (tc, mc) in zip(dup, clean, strict=True):
        types = {o.object_id: o.object_type for o in td.ground_truth.objects}
        capacity = Counter(types.values())
        mapped = Counter(types[o] for o in set(_planted_ids(tc, -1).values()))
        written = list(_planted_ids(td, -1).values())  # one id per label: copies repeat it
        extra = Counter(types[o] for o in written) - Counter(types[o] for o in set(written))
        predicted.append(sum(min(mapped[k] + extra[k], capacity[k]) for k in capacity) / len(types))
        recovered.append(md.aec)
        rises.append((md.aec or 0.0) - (mc.aec or 0.0))
    gap = max_gap(predicted, recovered)
    planted, measured = [], []
    for td, md in dup:
        ratio = _sir_ratio_planted(td)
        if ratio is not None and md.sir is not None and md.aec:
            planted.append(ratio)
            measured.append(md.sir / md.aec)
    want = float(np.mean(planted)) if planted else math.nan
    got = float(np.mean(measured)) if measured else math.nan
    sir_gap = max_gap(planted, measured) if planted else math.inf
    return [
        Check(
            section="Explore",
            name=f"AEC with duplicates, mimic-p{p:g}: Eq. AEC",
            planted="sum_k min(|M_k| + D_k, |E_k|) / |E|",
            recovered=f"max |diff| {fmt(gap, 4)}; mean rise {fmt(np.mean(rises), 4)}",
            tolerance="exactly; never lower than clean",
            verdict=judged(gap <= EXACT and min(rises) >= -EXACT),
            note=f"{len(dup)} paired episodes; D_k from the agent's state; a duplicate counts only "
            "where type k has an unmapped instance",
            data={"max_gap": gap, "mean_rise": float(np.mean(rises))},
        ),
        Check(
            section="Remember",
            name=f"SIR / AEC with duplicates, mimic-p{p:g}",
            planted=fmt(want, 3),
            recovered=f"{fmt(got, 3)}; max |diff| {fmt(sir_gap, 4)}",
            tolerance="exactly, per episode",
            verdict=judged(sir_gap <= EXACT),
            note=f"{len(planted)} episodes with a re-entry; planted: share of M_first without a "
            "duplicate at the re-entry's end (Appendix B: 'successfully deduplicated'); "
            "recovered: copies found by position (metrics reentry_copies)",
            data={"planted_ratio": want, "recovered_ratio": got, "max_gap": sir_gap},
        ),
    ]


def reply_checks(
    default: Sequence[Trajectory], clean: Sequence[Trajectory], planted: Mapping[str, float]
) -> list[Check]:
    """Parse failures, repaired replies and refused actions recover ``fail``, ``repair``,
    ``invalid`` of the default mimic."""
    steps = [s for t in default for s in t.steps]
    readable = [s for s in steps if s.parse_error is None]
    repaired = sum(bool(s.repairs) for s in readable)
    refused = sum(not s.success for s in readable)
    base = [s for t in clean for s in t.steps]
    f0 = sum(not s.success for s in base) / len(base)
    net = round((refused - f0 * len(readable)) / (1.0 - f0))
    kinds = Counter(r for s in readable for r in s.repairs or ())
    return [
        rate_check(
            "Replies",
            "Parse failures, mimic",
            planted["fail"],
            sum(s.parse_error is not None for s in steps),
            len(steps),
            "over all steps",
        ),
        rate_check(
            "Replies",
            "Replies read with a repair, mimic",
            planted["repair"],
            repaired,
            len(readable),
            "over readable replies; " + ", ".join(f"{k} {n}" for k, n in sorted(kinds.items())),
        ),
        rate_check(
            "Replies",
            "Invalid actions, mimic",
            planted["invalid"],
            max(net, 0),
            len(readable),
            f"refused {refused}, net of the clean mimic's own refusal rate {pct(f0)}",
        ),
    ]
