"""Remember-phase aggregates over many episodes: spells, KM, Ebbinghaus, SPE, Miller, SIR.

Every function takes trajectories or :class:`EpisodeMetrics` (mixed is fine), excludes
errored episodes and reports how many it excluded.
"""

from __future__ import annotations

import math
from collections import Counter
from collections.abc import Iterable
from dataclasses import dataclass
from itertools import pairwise

import numpy as np

from pytest_emrd.errors import check_positive_int
from pytest_emrd.metrics._episode import EpisodeLike, EpisodeMetrics, categories_of, split_errored
from pytest_emrd.metrics._scores import discovery_thirds
from pytest_emrd.metrics._stats import Anova, anova_groups
from pytest_emrd.metrics._survival import (
    AnchoredKM,
    EbbinghausFit,
    anchored_km,
    ebbinghaus_fit,
    efc,
)
from pytest_emrd.metrics._tracking import Spell


def forgetting_spells(items: Iterable[EpisodeLike]) -> tuple[Spell, ...]:
    """Every out-of-view spell of every non-errored episode (see :mod:`._tracking`)."""
    kept, _ = split_errored(items)
    return tuple(s for m in kept for s in m.spells)


@dataclass(frozen=True)
class TimeToForget:
    """Time-to-forget of every mapped object that left view (its first spell)."""

    spells: tuple[Spell, ...]
    events: int
    """Spells that ended in a forgetting event."""
    mean_observed: float | None
    """Mean duration over all spells, censored ones included (a lower bound of mean TTF)."""
    excluded: int
    """Errored episodes left out."""


def time_to_forget(items: Iterable[EpisodeLike]) -> TimeToForget:
    """Per-object time-to-forget, ``TTF_j``: the duration of each object's first spell.

    One spell per object (its first), so frequently re-seen objects do not weigh more. The
    naive mean treats censored spells as if they ended there; use :func:`ebbinghaus` for the
    censoring-aware estimate. No spells: ``mean_observed`` None.
    """
    kept, excluded = split_errored(items)
    spells = tuple(s for m in kept for s in m.ttf_spells)
    mean = math.fsum(s.duration for s in spells) / len(spells) if spells else None
    return TimeToForget(spells, sum(s.forgotten for s in spells), mean, excluded)


def _pooled(kept: list[EpisodeMetrics], category: str | None) -> tuple[list[Spell], float]:
    """First spells of ``category`` (None: all) and its coverage ``C`` = mapped / total."""
    spells = [s for m in kept for s in m.ttf_spells if category in (None, s.category)]

    def count(by_category: dict[str, int]) -> int:
        return sum(n for c, n in by_category.items() if category in (None, c))

    mapped = sum(count(m.mapped_by_category) for m in kept)
    total = sum(count(m.objects_by_category) for m in kept)
    return spells, (mapped / total if total else 0.0)


def pooled_fit(
    kept: list[EpisodeMetrics], category: str | None, points: str = "durations"
) -> EbbinghausFit:
    """:func:`ebbinghaus_fit` of the first spells of ``category`` (None: all) of ``kept``."""
    spells, coverage = _pooled(kept, category)
    return ebbinghaus_fit(
        [s.duration for s in spells], [s.forgotten for s in spells], coverage=coverage,
        points=points,
    )  # fmt: skip


def kaplan_meier_anchored(items: Iterable[EpisodeLike]) -> dict[str, AnchoredKM]:
    r"""Coverage-anchored Kaplan-Meier curve per memory category, pooled over episodes.

    .. math::
        \hat{S}_{\mathcal{X}}(t) = C_{\mathcal{X}} \prod_{\tau \le t}(1 - d_\tau / n_\tau),
        \qquad C_{\mathcal{X}} = \frac{\sum_i |\text{mapped}_{\mathcal{X}}^{(i)}|}
                                      {\sum_i |E_{\mathcal{X}}^{(i)}|}

    ``mapped`` counts objects held in the map at any step. Spells are each object's first
    (see :func:`time_to_forget`); see :func:`anchored_km` for censoring and ties. A category
    with ground truth but no spell gives the single point ``(0, C)``. Categories: those in the
    ground truth (landmark, salient, clutter first). No episodes: an empty dict.
    """
    kept, _ = split_errored(items)
    out: dict[str, AnchoredKM] = {}
    for category in categories_of(kept):
        spells, coverage = _pooled(kept, category)
        out[category] = anchored_km(
            [s.duration for s in spells], [s.forgotten for s in spells], coverage=coverage
        )
    return out


@dataclass(frozen=True)
class Ebbinghaus:
    """Ebbinghaus memory strength and fit per category, and pooled over categories."""

    by_category: dict[str, EbbinghausFit]
    pooled: EbbinghausFit
    """All categories together (the ``memory_strength`` / ``ebbinghaus_r2`` gates)."""
    excluded: int


def ebbinghaus(items: Iterable[EpisodeLike], *, points: str = "durations") -> Ebbinghaus:
    r"""Memory strength ``EFC = sum t_j / d`` (Eq. SMLE) and ``R^2`` against the anchored KM.

    Per category and pooled (``C`` of the pooled curve is mapped / total over all categories).
    No events in a category: EFC ``inf`` with a reason, never a crash; no spells: None. See
    :func:`ebbinghaus_fit` for the R^2 definition and its evaluation ``points`` (negative
    values are expected for abrupt, non-exponential forgetting).
    """
    kept, excluded = split_errored(items)
    by_category = {c: pooled_fit(kept, c, points) for c in categories_of(kept)}
    return Ebbinghaus(by_category, pooled_fit(kept, None, points), excluded)


@dataclass(frozen=True)
class SerialPosition:
    """Mean TTF of the Early / Middle / Late discovery thirds (Eq. SPE), and our
    censoring-aware estimate beside it (``mle_*``)."""

    early: float | None
    """The paper's estimator (Eq. SPE), steps; likewise ``middle`` and ``late``."""
    middle: float | None
    late: float | None
    n: tuple[int, int, int]
    """Episodes contributing to each bin of the paper's estimator."""
    excluded: int
    mle_early: float | None = None
    """Our addition: exponential MLE of the mean TTF of the Early third pooled over episodes,
    ``sum t_j / d`` (:func:`efc`), steps; ``inf`` with no forgetting event, None with no
    spell. Likewise ``mle_middle`` and ``mle_late``."""
    mle_middle: float | None = None
    mle_late: float | None = None
    spells: tuple[int, int, int] = (0, 0, 0)
    """First spells per third (objects that left view while mapped)."""
    events: tuple[int, int, int] = (0, 0, 0)
    """Forgetting events (uncensored spells) per third."""


def serial_position(items: Iterable[EpisodeLike]) -> SerialPosition:
    r"""Serial Position Effect across episodes (Eq. SPE), with a censoring-aware estimate.

    .. math::
        \overline{TTF}_b = \frac{1}{N_b} \sum_{i} \frac{1}{|\mathcal{D}_b^{(i)}|}
            \sum_{j \in \mathcal{D}_b^{(i)}} TTF_j^{(i)},
        \qquad
        \widehat{TTF}_b^{MLE} = \frac{\sum_i \sum_{j \in \mathcal{D}_b^{(i)}} t_j}
            {\sum_i \sum_{j \in \mathcal{D}_b^{(i)}} \delta_j}

    **Paper's estimator** (``early``, ``middle``, ``late``): per-episode bin means come from
    :func:`serial_position_bins`; an episode whose bin is undefined (no object of the bin
    left view) is left out of that bin's mean, so ``N_b`` may differ between bins (``n``).
    ``TTF_j`` is the first spell's duration, censored or not, as in the paper. It is biased
    low wherever spells are right-censored, and most for the Late third: an object found
    near the end of the episode can only be retained for the few steps that remain, so even
    a perfect memory shows ``E > M > L``.

    **Censoring-aware estimate** (``mle_*``, our addition): per third, the first spells of
    every episode are pooled and the exponential maximum-likelihood mean ``sum t_j / d`` is
    taken (:func:`efc`; ``delta_j = 1`` for a forgetting event), which counts a censored
    spell as survival, not as forgetting. It assumes non-informative censoring and a
    constant hazard within a third. A third without forgetting events is ``inf`` (nothing
    was forgotten: protected), one without spells None.

    No episode for a bin: None. Thirds are those of :func:`discovery_thirds` over each
    episode's discovered objects.
    """
    kept, excluded = split_errored(items)
    means: list[float | None] = []
    counts: list[int] = []
    for b in range(3):
        values = [v for m in kept if (v := m.serial_position[b]) is not None]
        means.append(math.fsum(values) / len(values) if values else None)
        counts.append(len(values))
    durations: list[list[int]] = [[], [], []]
    forgotten: list[list[bool]] = [[], [], []]
    for m in kept:
        third = discovery_thirds(sum(m.mapped_by_category.values()))
        for s in m.ttf_spells:
            b = int(third[s.discovery_rank - 1])
            durations[b].append(s.duration)
            forgotten[b].append(s.forgotten)
    mle = [efc(durations[b], forgotten[b]) for b in range(3)]
    return SerialPosition(
        means[0], means[1], means[2], (counts[0], counts[1], counts[2]), excluded,
        mle[0], mle[1], mle[2],
        (len(durations[0]), len(durations[1]), len(durations[2])),
        (sum(forgotten[0]), sum(forgotten[1]), sum(forgotten[2])),
    )  # fmt: skip


@dataclass(frozen=True)
class MillerCurve:
    """Forgetting probability by cognitive-load bin (Eq. MillerLaw)."""

    width: int
    """Bin width ``w``."""
    bins: tuple[int, ...]
    """Non-empty bins ``b = ceil(m / w)``, ascending."""
    probabilities: tuple[float, ...]
    """``ML(b)`` per bin, in [0, 1]."""
    steps: tuple[int, ...]
    """Steps per bin (the denominator)."""
    events: tuple[int, ...]
    """Steps with a forgetting event per bin (the numerator)."""
    b_star: int | None
    """Inflection bin: the largest rise between consecutive eligible bins, the first eligible
    bin's rise measured from the anchor ``ML(0) = 0``."""
    m_star: int | None
    """Effective capacity ``m* = b* w``."""
    reason: str | None = None


def miller_curve(
    items: Iterable[EpisodeLike], *, width: int = 5, min_steps: int = 1
) -> MillerCurve:
    r"""Miller's-law forgetting probability by load bin (Eq. MillerLaw).

    .. math::
        \overline{ML}(b) = \frac{\sum_i \sum_{t: \lceil |M_{t-1}| / w \rceil = b}
            \mathbb{1}_{forget}(t)}{\sum_i \sum_{t: \lceil |M_{t-1}| / w \rceil = b} 1},
        \qquad b^* = \arg\max_b \left(\overline{ML}(b) - \overline{ML}(b')\right)

    ``m = |M_{t-1}|`` counts distinct labels; ``1_forget(t)`` is 1 when any label of
    ``M_{t-1}`` is missing from ``M_t``. Steps with an empty previous map are not counted.

    **Inflection** ``b*``: among bins with at least ``min_steps`` steps (*eligible*), the bin
    with the largest positive rise ``ML(b) - ML(b')`` over the previous eligible bin ``b'``
    (earliest on ties); ``m* = b* w``. The first eligible bin's rise is measured from the
    **anchor** ``ML(0) = 0``: by ``b = ceil(m / w)`` bin 0 holds only ``m = 0``, and with an
    empty map nothing can be forgotten, so ``ML(0) = 0`` by definition rather than by
    measurement. Without the anchor a capacity at or below ``w`` (every load in bin 1) could
    never show an inflection, however sharply it forgets; with it a curve already high in
    its first bin puts ``b*`` there. The paper's example 0.05, 0.08, 0.65 gives rises 0.05,
    0.03, 0.57, so ``b* = 3`` and ``m* = 15``.

    Edge cases: no positive rise (a curve that is 0 everywhere, or only falls) gives ``b*``
    and ``m*`` None with a reason; no eligible bin gives None with a reason; no step at all
    gives an empty curve with a reason.
    """
    check_positive_int("width", width)
    check_positive_int("min_steps", min_steps)
    kept, _ = split_errored(items)
    loads = np.array([x for m in kept for x in m.miller_loads], dtype=np.int64)
    forgets = np.array([x for m in kept for x in m.miller_forgets], dtype=bool)
    if not len(loads):
        return MillerCurve(width, (), (), (), (), None, None, "no step with a non-empty map")
    b = -(-loads // width)
    steps = np.bincount(b)
    events = np.bincount(b, weights=forgets.astype(float)).astype(np.int64)
    bins = np.flatnonzero(steps)
    probs = events[bins] / steps[bins]
    eligible = [(0, 0.0)] + [(int(bins[i]), float(probs[i])) for i in range(len(bins))
                             if steps[bins[i]] >= min_steps]  # fmt: skip
    rises = [(p - p_prev, b_now) for (_, p_prev), (b_now, p) in pairwise(eligible)]
    best = max(rises, key=lambda r: r[0], default=(0.0, 0))
    b_star = int(best[1]) if best[0] > 0 else None
    reason = None
    if b_star is None:
        reason = "no rise between consecutive load bins (from ML(0) = 0): no inflection"
        if len(eligible) < 2:
            reason = f"no load bin with >= {min_steps} steps: no inflection"
    return MillerCurve(
        width,
        tuple(bins.tolist()),
        tuple(float(p) for p in probs),
        tuple(steps[bins].tolist()),
        tuple(events[bins].tolist()),
        b_star,
        None if b_star is None else b_star * width,
        reason,
    )


@dataclass(frozen=True)
class SpatialIdentityResolution:
    """Per-episode SIR values and why the others are undefined."""

    values: tuple[float, ...]
    """SIR of every episode where it is defined."""
    mean: float | None
    undefined: dict[str, int]
    """Reason -> episodes (e.g. ``no room was re-entered``)."""
    excluded: int
    """Errored episodes left out."""


def spatial_identity_resolution(items: Iterable[EpisodeLike]) -> SpatialIdentityResolution:
    """SIR per episode (see :func:`sir_score`), with undefined episodes counted by reason."""
    kept, excluded = split_errored(items)
    values = tuple(m.sir for m in kept if m.sir is not None)
    undefined = Counter(m.reasons.get("sir", "undefined") for m in kept if m.sir is None)
    mean = math.fsum(values) / len(values) if values else None
    return SpatialIdentityResolution(values, mean, dict(undefined), excluded)


def anova_conditions(items: Iterable[EpisodeLike]) -> Anova:
    """One-way ANOVA of per-episode memory strength across conditions (statsmodels).

    Each episode's EFC is ``sum t_j / d`` over its objects' first spells. Episodes with no
    spell (None) or no forgetting event (``inf``) carry no finite strength and are left out
    (the ``groups`` sizes show what was used). See :func:`anova_groups` for degenerate cases.
    """
    kept, _ = split_errored(items)
    groups: dict[str, list[float]] = {}
    for m in kept:
        strength = m.memory_strength
        if strength is not None and math.isfinite(strength):
            groups.setdefault(m.spec.condition, []).append(strength)
    return anova_groups(groups)
