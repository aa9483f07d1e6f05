"""Remember rows: Ebbinghaus memory strength, Miller's law and serial position recover what
the reference agents plant (:mod:`pytest_emrd.reference._memory`).

Do the R^2 findings survive the choice of evaluation points? The paper compares the
Ebbinghaus and Kaplan-Meier curves by R^2 without saying at which times; our default uses
the KM timeline (``points="durations"``). :func:`r2_points_checks` recomputes the two R^2
findings (planted decay fits, R^2 >= :data:`MIN_R2`; a hard window fits worse than the decay
of matched mean, gap >= :data:`R2_GAP`) on every grid of
:data:`~pytest_emrd.metrics.R2_POINTS`: a finding that fails an alternative grid is a
``finding`` on that row.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Final

from pytest_emrd.metrics import (
    R2_POINTS,
    EbbinghausFit,
    SerialPosition,
    ebbinghaus,
    miller_curve,
    serial_position,
)
from pytest_emrd.rooms import ROOM_SLUGS
from pytest_emrd.validate._check import Check, Episodes, Value, fmt, judged

#: Planted mean -> its ``scout-decay`` episodes.
Decays = Mapping[float, Episodes]
#: Planted capacity -> its ``scout-window`` episodes.
Windows = Mapping[int, Episodes]

#: Ebbinghaus EFC must recover the planted mean within this relative error.
EFC_TOLERANCE: Final = 0.25
#: Minimum R^2 of the exponential fit for a planted exponential memory.
MIN_R2: Final = 0.8
#: A hard-capacity memory must fit the exponential at least this much worse (R^2) than a
#: planted exponential memory of about the same strength.
R2_GAP: Final = 0.1
#: Miller's inflection bin must lie within this many bins of the planted capacity's bin.
MILLER_BINS: Final = 1
#: Load-bin width ``w`` (the paper's 5).
MILLER_WIDTH: Final = 5
#: Relative slack of the serial-position shape tests (:func:`monotone`, flat).
SERIAL_TOLERANCE: Final = 0.1
#: A Middle-third dip (:func:`u_depth`) at least this deep is a U. Protecting whole thirds,
#: as ``scout-serial`` does, gives about 1; the paper calls a 0.14 dip flat (Ovis2-34B,
#: E/M/L 5.0/4.3/5.4); an LRU window dips 0.0-0.25 from path density alone. Halfway.
MAX_U_DEPTH: Final = 0.5

_SPAWN_ORDER: Final = {slug: i for i, slug in enumerate(ROOM_SLUGS.values())}


def error_curve(trajectories: Episodes, planted: float) -> list[tuple[int, float]]:
    """``(N, |EFC_N - planted| / planted)`` over spawn-balanced prefixes of N = 4, 8, ...
    episodes; a prefix whose EFC is undefined has error ``inf``.

    :param trajectories: One group's episodes, spawn-major.
    :param planted: The planted mean EFC.
    :returns: ``(N, relative error)`` pairs.
    """
    ordered = sorted(trajectories, key=lambda t: (t.spec.episode, _SPAWN_ORDER[t.spec.spawn]))
    curve = []
    for n in range(4, len(ordered) + 1, 4):
        efc = ebbinghaus(ordered[:n]).pooled.efc
        curve.append((n, abs(efc - planted) / planted if efc is not None else math.inf))
    return curve


def episodes_needed(curve: Sequence[tuple[int, float]], tolerance: float) -> int | None:
    """Smallest N from which every larger prefix stays within ``tolerance`` (None: never).

    :param curve: ``(N, error)`` pairs by increasing N (:func:`error_curve`).
    :param tolerance: The largest relative error accepted.
    :returns: The smallest such N, or None.
    """
    needed = None
    for n, error in reversed(curve):
        if error > tolerance:
            break
        needed = n
    return needed


def decay_checks(groups: Decays) -> list[Check]:
    """EFC within 25 % of the planted mean and R^2 >= 0.8, per ``scout-decay-<m>`` group.

    :param groups: Planted mean -> its ``scout-decay`` episodes.
    :returns: One :class:`Check` per group.
    """
    rows: list[Check] = []
    for mean, trajs in groups.items():
        fit = ebbinghaus(trajs).pooled
        curve = error_curve(trajs, mean)
        needed = episodes_needed(curve, EFC_TOLERANCE)
        error = abs(fit.efc - mean) / mean if fit.efc is not None else math.inf
        shrink = ", ".join(f"N={n}: {100 * e:.0f} %" for n, e in curve[:: max(1, len(curve) // 5)])
        note = (
            f"{len(trajs)} episodes, {fit.n_events}/{fit.n_spells} spells forgotten; planted: "
            f"dropped with probability 1/{mean:g} per out-of-view step (geometric, mean "
            f"{mean:g}); within 25 % from N = {needed if needed is not None else 'never'} "
            f"(error {shrink})"
        )
        rows += [
            Check(
                section="Remember",
                name=f"Ebbinghaus EFC, scout-decay-{mean:g}",
                planted=f"{mean:g} steps",
                recovered=f"{fmt(fit.efc)} steps ({100 * error:.0f} % off)",
                tolerance="within 25 %",
                verdict=judged(error <= EFC_TOLERANCE),
                note=note,
                data={
                    "efc": fit.efc,
                    "r2": fit.r2,
                    "error": error,
                    "episodes_needed": needed,
                    **{f"error_n{n}": e for n, e in curve},
                },
            ),
            Check(
                section="Remember",
                name=f"Ebbinghaus R^2, scout-decay-{mean:g}",
                planted="exponential",
                recovered=f"R^2 = {fmt(fit.r2, 3)}",
                tolerance=f">= {MIN_R2}",
                verdict=judged(fit.r2 is not None and fit.r2 >= MIN_R2),
                note=f"{len(trajs)} episodes; R^2 of C exp(-t/EFC) against the anchored KM",
                data={"r2": fit.r2},
            ),
        ]
    return rows


def nearest_decay(fit: EbbinghausFit, decays: Mapping[float, EbbinghausFit]) -> float | None:
    """The planted mean whose decay fit has the finite EFC nearest ``fit``'s (on a log scale);
    None when ``fit`` or every decay has no finite EFC."""
    finite = [m for m, f in decays.items() if f.efc and math.isfinite(f.efc)]
    if fit.efc is None or not math.isfinite(fit.efc) or not finite:
        return None
    efc = fit.efc
    return min(finite, key=lambda m: abs(math.log(decays[m].efc or 1.0) - math.log(efc)))


def window_fit_checks(windows: Windows, decays: Decays) -> list[Check]:
    """Each ``scout-window-<k>`` fits the exponential visibly worse than the ``scout-decay``
    whose recovered EFC is nearest its own (matched mean).

    :param windows: Capacity -> ``scout-window`` episodes.
    :param decays: Planted mean -> ``scout-decay`` episodes, the comparison.
    :returns: One :class:`Check` per window.
    """
    decay_fits = {m: ebbinghaus(t).pooled for m, t in decays.items()}
    rows = []
    for k, trajs in windows.items():
        fit = ebbinghaus(trajs).pooled
        m = nearest_decay(fit, decay_fits)
        if m is None:
            rows.append(
                Check(
                    section="Remember",
                    name=f"Exponential fit, scout-window-{k} vs scout-decay",
                    planted="worse fit",
                    recovered="n/a",
                    tolerance=f"R^2 gap >= {R2_GAP}",
                    verdict="fail",
                    note=f"no finite EFC to match (window EFC {fmt(fit.efc)})",
                )
            )
            continue
        match = decay_fits[m]
        gap = (match.r2 or 0.0) - fit.r2 if fit.r2 is not None else math.inf
        rows.append(
            Check(
                section="Remember",
                name=f"Exponential fit, scout-window-{k} vs scout-decay-{m:g}",
                planted=f"R^2 below {fmt(match.r2, 3)}",
                recovered=f"R^2 = {fmt(fit.r2, 3)}",
                tolerance=f"gap >= {R2_GAP}",
                verdict=judged(gap >= R2_GAP),
                note=f"matched mean: window EFC {fmt(fit.efc)} vs decay EFC {fmt(match.efc)} "
                f"steps; {len(trajs)} + {len(decays[m])} episodes",
                data={
                    "r2_window": fit.r2,
                    "r2_decay": match.r2,
                    "efc_window": fit.efc,
                    "efc_decay": match.efc,
                },
            )
        )
    return rows


def miller_checks(windows: Windows, perfect: Episodes) -> list[Check]:
    """Inflection ``m*`` within one bin of each planted capacity; perfect memory never
    forgets at any load.

    :param windows: Planted capacity -> its ``scout-window`` episodes.
    :param perfect: Episodes with perfect memory.
    :returns: One :class:`Check` per capacity, then the perfect-memory row.
    """
    rows = []
    for k, trajs in windows.items():
        curve = miller_curve(trajs, width=MILLER_WIDTH)
        want = math.ceil(k / MILLER_WIDTH)
        probs = ", ".join(
            f"{b}: {p:.2f}" for b, p in zip(curve.bins, curve.probabilities, strict=True)
        )
        rows.append(
            Check(
                section="Remember",
                name=f"Miller inflection, scout-window-{k}",
                planted=f"m* = {k} (bin {want})",
                recovered=f"m* = {curve.m_star if curve.m_star is not None else 'none'}",
                tolerance=f"within {MILLER_BINS} bin (w = {MILLER_WIDTH})",
                verdict=judged(
                    curve.b_star is not None and abs(curve.b_star - want) <= MILLER_BINS
                ),
                note=f"{len(trajs)} episodes; ML(bin) {probs}"
                + (f"; {curve.reason}" if curve.reason else ""),
                data={"m_star": curve.m_star, "b_star": curve.b_star, "planted_bin": want},
            )
        )
    curve = miller_curve(perfect, width=MILLER_WIDTH)
    worst = max(curve.probabilities, default=None)
    rows.append(
        Check(
            section="Remember",
            name="Miller forgetting, scout (perfect memory)",
            planted="0 at every load",
            recovered=f"max ML = {fmt(worst)}",
            tolerance="exactly 0",
            verdict=judged(worst == 0.0),
            note=f"{len(perfect)} episodes, {sum(curve.steps)} steps over {len(curve.bins)} load "
            "bins",
            data={"max_probability": worst, "bins": len(curve.bins)},
        )
    )
    return rows


def _profile(early: float | None, middle: float | None, late: float | None) -> str:
    return f"E {fmt(early)}, M {fmt(middle)}, L {fmt(late)}"


def monotone(early: float | None, middle: float | None, late: float | None) -> bool:
    """Monotone within ``tau`` (:data:`SERIAL_TOLERANCE`): all thirds defined and
    ``min(E, L) / (1 + tau) <= M <= max(E, L) (1 + tau)``. Admits non-decreasing,
    non-increasing and flat profiles (``inf``: no forgetting), rejects a U or an inverted U.

    :param early: Early third's value.
    :param middle: Middle third's value.
    :param late: Late third's value.
    :returns: Whether the profile is monotone within the tolerance.
    """
    if early is None or middle is None or late is None:
        return False
    slack = 1.0 + SERIAL_TOLERANCE
    return min(early, late) / slack <= middle <= max(early, late) * slack


def u_depth(early: float | None, middle: float | None, late: float | None) -> float | None:
    """How deep the Middle third dips below the nearer end: ``max(0, 1 - M / min(E, L))``;
    0 for no dip, 1 for ``inf`` ends and a finite ``M``, None when a third is undefined.

    :param early: Early third's value (``inf`` allowed).
    :param middle: Middle third's value.
    :param late: Late third's value.
    :returns: The depth in [0, 1], or None.
    """
    if early is None or middle is None or late is None:
        return None
    ends = min(early, late)
    if math.isinf(middle) or middle >= ends:
        return 0.0
    return 1.0 - middle / ends if math.isfinite(ends) else 1.0


def _paper_note(spe: SerialPosition, episodes: int) -> str:
    return (
        f"{episodes} episodes; MLE = sum t / d per discovery third "
        f"({'/'.join(map(str, spe.events))} of {'/'.join(map(str, spe.spells))} first spells "
        f"forgotten); the paper's Eq. SPE (censored TTF averaged) gives "
        f"{_profile(spe.early, spe.middle, spe.late)}"
    )


def _data(spe: SerialPosition) -> dict[str, Value]:
    return {
        "early": spe.mle_early,
        "middle": spe.mle_middle,
        "late": spe.mle_late,
        "paper_early": spe.early,
        "paper_middle": spe.middle,
        "paper_late": spe.late,
    }


_LRU_SHAPE: Final = (
    "no: an LRU window drops an object once k others are seen after it, so its retention "
    "follows how densely the path shows new objects, not discovery rank"
)


def serial_checks(
    serial: Episodes,
    windows: Windows,
    perfect: Episodes = (),
) -> list[Check]:
    """Serial position on the censoring-aware estimate (``mle_*``, the paper's beside it):
    ``scout-serial`` shows the U (E, L > M); no ``scout-window`` does (:func:`u_depth` below
    :data:`MAX_U_DEPTH`, :func:`monotone` noted); with ``perfect`` episodes, a row on the
    paper's estimator under perfect memory (its censoring bias).

    :param serial: The ``scout-serial`` episodes.
    :param windows: Capacity -> ``scout-window`` episodes.
    :param perfect: Episodes with perfect memory; empty for no such row.
    :returns: The serial-position :class:`Check` rows.
    """
    spe = serial_position(serial)
    e, m, late = spe.mle_early, spe.mle_middle, spe.mle_late
    u_shape = e is not None and m is not None and late is not None and min(e, late) > m
    depth = u_depth(e, m, late)
    rows = [
        Check(
            section="Remember",
            name="Serial position, scout-serial",
            planted="U shape (E, L > M)",
            recovered=f"MLE {_profile(e, m, late)}; U depth {fmt(depth)}",
            tolerance="E > M and L > M (MLE)",
            verdict=judged(u_shape),
            note=_paper_note(spe, len(serial)),
            data={**_data(spe), "u_depth": depth},
        )
    ]
    for k, trajs in windows.items():
        spe = serial_position(trajs)
        values = (spe.mle_early, spe.mle_middle, spe.mle_late)
        depth = u_depth(*values)
        shape = "yes" if monotone(*values) else _LRU_SHAPE
        rows.append(
            Check(
                section="Remember",
                name=f"Serial position, scout-window-{k}",
                planted="no U (LRU plants none)",
                recovered=f"MLE {_profile(*values)}; U depth {fmt(depth)}",
                tolerance=f"U depth < {MAX_U_DEPTH:g} (planted U ~ 1)",
                verdict=judged(depth is not None and depth < MAX_U_DEPTH),
                note=f"{_paper_note(spe, len(trajs))}; monotone within "
                f"{SERIAL_TOLERANCE:.0%}: {shape}",
                data={**_data(spe), "u_depth": depth},
            )
        )
    if perfect:
        rows.append(_censoring_bias(serial_position(perfect), len(perfect)))
    return rows


def _censoring_bias(spe: SerialPosition, episodes: int) -> Check:
    """Perfect memory forgets nothing: the MLE must say so in every third (else ``fail``); a
    paper profile that is not flat there is the estimator's bias (``finding``)."""
    mle = (spe.mle_early, spe.mle_middle, spe.mle_late)
    paper = (spe.early, spe.middle, spe.late)
    never = all(v is not None and math.isinf(v) for v in mle)
    defined = [v for v in paper if v is not None]
    flat = len(defined) == len(paper) and max(defined) <= min(defined) * (1.0 + SERIAL_TOLERANCE)
    verdict = "fail" if not never else ("pass" if flat else "finding")
    note = (
        f"{episodes} episodes, {sum(spe.events)} of {sum(spe.spells)} first spells forgotten; "
        "Eq. SPE averages right-censored TTF, so an object found late can only be retained "
        "for the steps left: a memory that never forgets shows E > M > L"
    )
    return Check(
        section="Remember",
        name="Serial position, Eq. SPE under perfect memory (scout)",
        planted="flat: nothing forgotten",
        recovered=f"paper {_profile(*paper)}; MLE {_profile(*mle)}",
        tolerance=f"MLE inf in every third; paper flat within {SERIAL_TOLERANCE:.0%}",
        verdict=verdict,
        note=note,
        data=_data(spe),
    )


def r2_points_checks(
    decays: Decays,
    windows: Windows,
    serial: Episodes,
) -> list[Check]:
    """One row per grid of :data:`~pytest_emrd.metrics.R2_POINTS` (the default first).

    :param decays: Planted mean -> ``scout-decay`` episodes.
    :param windows: Capacity -> ``scout-window`` episodes.
    :param serial: The ``scout-serial`` episodes.
    :returns: One :class:`Check` per grid.
    """
    rows = []
    for points in R2_POINTS:
        decay = {m: ebbinghaus(t, points=points).pooled for m, t in decays.items()}
        window = {k: ebbinghaus(t, points=points).pooled for k, t in windows.items()}
        r2_serial = ebbinghaus(serial, points=points).pooled.r2
        exponential = all(f.r2 is not None and f.r2 >= MIN_R2 for f in decay.values())
        gaps = []
        for fit in window.values():
            m = nearest_decay(fit, decay)
            gaps.append(-math.inf if m is None or fit.r2 is None else (decay[m].r2 or 0.0) - fit.r2)
        survives = exponential and all(g >= R2_GAP for g in gaps)
        default = points == R2_POINTS[0]
        verdict = "pass" if survives else ("fail" if default else "finding")
        decay_r2 = " / ".join(fmt(f.r2, 2) for f in decay.values())
        window_r2 = " / ".join(fmt(f.r2, 2) for f in window.values())
        rows.append(
            Check(
                section="Remember",
                name=f"R^2 findings on evaluation points '{points}'"
                + (" (default)" if default else ""),
                planted=f"decay R^2 >= {MIN_R2}; window gap >= {R2_GAP}",
                recovered=f"decay {decay_r2}; window {window_r2}; serial {fmt(r2_serial, 2)}",
                tolerance="both findings hold",
                verdict=verdict,
                note=f"decay {', '.join(f'{m:g}' for m in decay)}; window "
                f"{', '.join(str(k) for k in window)}; smallest gap "
                f"{fmt(min(gaps, default=math.nan), 2)}",
                data={
                    "points": points,
                    "min_gap": min(gaps, default=math.nan),
                    "serial_r2": r2_serial,
                    **{f"r2_decay_{m:g}": f.r2 for m, f in decay.items()},
                    **{f"r2_window_{k}": f.r2 for k, f in window.items()},
                },
            )
        )
    return rows
