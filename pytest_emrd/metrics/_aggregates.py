"""Aggregates over many episodes, by phase.

Explore and Map: per-episode positional accuracy and the TBS curve. Remember: spells, KM,
Ebbinghaus, SPE, Miller, SIR, ANOVA. Decide: focal-point distribution by spawn, consensus,
FPSG summary. Every function takes trajectories or :class:`EpisodeMetrics` (mixed is fine),
excludes errored episodes and reports how many it excluded.
"""

from __future__ import annotations

import math
import statistics
from collections import Counter
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from itertools import pairwise

import numpy as np

from pytest_emrd.errors import check_positive_int
from pytest_emrd.metrics._episode import (
    EpisodeLike,
    EpisodeMetrics,
    as_episode_metrics,
    categories_of,
    discovery_thirds,
    split_errored,
)
from pytest_emrd.metrics._stats import (
    AnchoredKM,
    Anova,
    EbbinghausFit,
    anchored_km,
    anova_groups,
    ebbinghaus_fit,
    efc,
)
from pytest_emrd.metrics._tracking import Spell
from pytest_emrd.rooms import FOCAL_COLUMNS, OTHER_LETTER, SLUG_ROOMS, room_letter


def positional_accuracy(items: Iterable[EpisodeLike]) -> tuple[float | None, ...]:
    """Positional Accuracy (Eq. PA) of each episode, in input order: None for an errored
    episode or ``|G_base| = 0`` (formula and edge cases: :func:`positional_accuracy_score`).

    :param items: Trajectories or their :class:`EpisodeMetrics`.
    :returns: ``PA`` in [0, 1] or None, one per item.
    """
    return tuple(m.pa for m in as_episode_metrics(items))


@dataclass(frozen=True)
class TBSCurve:
    """Mean Temporal Belief Stability per step."""

    t: tuple[int, ...]
    """Steps ``1..T_max``."""
    mean: tuple[float, ...]
    """``TBS(t)`` averaged over episodes (carry-forward beyond an episode's last step)."""
    sd: tuple[float, ...]
    """Population standard deviation across episodes at each step."""
    n: int
    """Episodes averaged."""
    excluded: int
    """Episodes left out: errored, without steps, or with ``|G_base| = 0``."""


def tbs_curve(items: Iterable[EpisodeLike], *, t_max: int | None = None) -> TBSCurve:
    r"""Temporal Belief Stability curve (Eq. TBS), averaged over episodes.

    .. math::
        TBS^{(i)}(t) = \exp\!\left(-\frac{\Delta d^{(i)}(t)}{L_{gt}^{(i)}}\right)
            \frac{|M_t^{(i)}|}{|G_{base}|},\qquad
        \Delta d^{(i)}(t) = \frac{1}{|M_t^{(i)}|} \sum_{j \in M_t^{(i)}}
            \|\hat{p}_j^{(t)} - \hat{p}_j^{(t_{first})}\|_2

    ``M_t`` are the entries of the step-``t`` map matched to ground truth, followed by label;
    ``t_first`` is the step the label was first written; ``L_gt`` is the RMS spread of the
    whole layout (the paper's "layout's root-mean-square scale"); the coverage factor is capped
    at 1. A step with nothing matched scores 0 (coverage 0). **Carry-forward:** an episode that
    ended (``Term``) before ``t`` keeps its last value, so an agent that stops early with a
    good map is not averaged as if it had forgotten everything; its curve is flat from then on.
    ``t_max`` defaults to the largest ``max_steps`` of the episodes. No usable episode: empty
    curve.

    :param items: The episodes to average; errored ones are left out.
    :param t_max: Last step of the curve; None for the largest ``max_steps``.
    :returns: A :class:`TBSCurve`: mean and sd of ``TBS(t)`` for ``t = 0..t_max``, and ``n``.
    """
    kept, errored = split_errored(items)
    usable = [m for m in kept if m.tbs]
    excluded = errored + len(kept) - len(usable)
    horizon = t_max if t_max is not None else max((m.spec.max_steps for m in usable), default=0)
    if not usable or horizon < 1:
        return TBSCurve((), (), (), 0, excluded)
    grid = np.array([(m.tbs + m.tbs[-1:] * horizon)[:horizon] for m in usable], dtype=float)
    mean, sd = tuple(grid.mean(axis=0).tolist()), tuple(grid.std(axis=0).tolist())
    return TBSCurve(tuple(range(1, horizon + 1)), mean, sd, len(usable), excluded)


def forgetting_spells(items: Iterable[EpisodeLike]) -> tuple[Spell, ...]:
    """Every out-of-view spell of every non-errored episode (see :mod:`._tracking`).

    :param items: Trajectories or :class:`EpisodeMetrics`; errored episodes contribute none.
    :returns: The spells, episode by episode in input order.
    """
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

    :param items: The episodes whose objects' first spells are pooled.
    :returns: A :class:`TimeToForget`: the first spells, their events and the naive mean.
    """
    kept, excluded = split_errored(items)
    spells = tuple(s for m in kept for s in m.ttf_spells)
    mean = statistics.fmean(s.duration for s in spells) if spells else None
    return TimeToForget(spells, sum(s.forgotten for s in spells), mean, excluded)


def _pooled(
    kept: list[EpisodeMetrics], category: str | None
) -> tuple[list[int], list[bool], float]:
    """Durations and events of the first spells of ``category`` (None: all) and its
    coverage ``C`` = mapped / total."""
    spells = [s for m in kept for s in m.ttf_spells if category in (None, s.category)]

    def count(by_category: dict[str, int]) -> int:
        return sum(n for c, n in by_category.items() if category in (None, c))

    mapped = sum(count(m.mapped_by_category) for m in kept)
    total = sum(count(m.objects_by_category) for m in kept)
    coverage = mapped / total if total else 0.0
    return [s.duration for s in spells], [s.forgotten for s in spells], coverage


def pooled_fit(
    kept: list[EpisodeMetrics], category: str | None, points: str = "durations"
) -> EbbinghausFit:
    """:func:`ebbinghaus_fit` of the first spells of ``category`` (None: all) of ``kept``."""
    durations, forgotten, coverage = _pooled(kept, category)
    return ebbinghaus_fit(durations, forgotten, coverage=coverage, points=points)


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

    :param items: The episodes pooled into each category's curve and anchor ``C``.
    :returns: Category name -> :class:`AnchoredKM`, ground-truth categories only.
    """
    kept, _ = split_errored(items)
    pooled = {category: _pooled(kept, category) for category in categories_of(kept)}
    return {c: anchored_km(t, e, coverage=cov) for c, (t, e, cov) in pooled.items()}


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

    :param items: The episodes whose first spells are pooled per category.
    :param points: Where ``R^2`` is evaluated: ``"durations"``, ``"steps"`` or ``"events"``.
    :returns: An :class:`Ebbinghaus`: EFC and ``R^2`` per category and pooled, with reasons.
    """
    kept, excluded = split_errored(items)
    by_category = {c: pooled_fit(kept, c, points) for c in categories_of(kept)}
    return Ebbinghaus(by_category, pooled_fit(kept, None, points), excluded)


@dataclass(frozen=True, kw_only=True)
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
    """Our censoring-aware estimate of the Early third (steps; see :func:`serial_position`).
    Likewise ``mle_middle`` and ``mle_late``."""
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

    **Paper's estimator** (``early``, ``middle``, ``late``): the per-episode bin means of
    :func:`serial_position_bins`; an episode whose bin is undefined (no object of the bin
    left view) is left out of that bin's mean, so ``N_b`` may differ between bins (``n``).
    ``TTF_j`` is the first spell's duration, censored or not, as in the paper: biased low
    wherever spells are right-censored, most for the Late third (an object found near the end
    can only be retained for the steps that remain, so even a perfect memory shows
    ``E > M > L``).

    **Censoring-aware estimate** (``mle_*``, ours): per third, the first spells of every
    episode pooled into the exponential MLE ``sum t_j / d`` (:func:`efc`; ``delta_j = 1`` for
    a forgetting event), which counts a censored spell as survival. It assumes
    non-informative censoring and a constant hazard within a third. A third without
    forgetting events is ``inf``, one without spells None.

    No episode for a bin: None. Thirds are those of :func:`discovery_thirds` over each
    episode's discovered objects.

    :param items: The episodes; each contributes its own bin means and its first spells.
    :returns: A :class:`SerialPosition`: both estimators per third, with ``n`` per bin.
    """
    kept, excluded = split_errored(items)
    bins = [[v for m in kept if (v := m.serial_position[b]) is not None] for b in range(3)]
    means = [statistics.fmean(values) if values else None for values in bins]
    thirds: list[list[Spell]] = [[], [], []]
    for m in kept:
        third = discovery_thirds(sum(m.mapped_by_category.values()))
        for s in m.ttf_spells:
            thirds[int(third[s.discovery_rank - 1])].append(s)
    mle = [efc([s.duration for s in ss], [s.forgotten for s in ss]) for ss in thirds]
    early, middle, late = ([s.forgotten for s in ss] for ss in thirds)
    return SerialPosition(
        early=means[0],
        middle=means[1],
        late=means[2],
        n=(len(bins[0]), len(bins[1]), len(bins[2])),
        excluded=excluded,
        mle_early=mle[0],
        mle_middle=mle[1],
        mle_late=mle[2],
        spells=(len(early), len(middle), len(late)),
        events=(sum(early), sum(middle), sum(late)),
    )


@dataclass(frozen=True, kw_only=True)
class MillerCurve:
    """Forgetting probability by cognitive-load bin (Eq. MillerLaw)."""

    width: int
    """Bin width ``w``."""
    bins: tuple[int, ...] = ()
    """Non-empty bins ``b = ceil(m / w)``, ascending (none: an empty curve)."""
    probabilities: tuple[float, ...] = ()
    """``ML(b)`` per bin, in [0, 1]."""
    steps: tuple[int, ...] = ()
    """Steps per bin (the denominator)."""
    events: tuple[int, ...] = ()
    """Steps with a forgetting event per bin (the numerator)."""
    b_star: int | None = None
    """Inflection bin (see :func:`miller_curve`)."""
    m_star: int | None = None
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
    **anchor** ``ML(0) = 0`` (bin 0 holds only ``m = 0``, and an empty map forgets nothing):
    without it a capacity at or below ``w`` could never show an inflection. The paper's
    example 0.05, 0.08, 0.65 gives rises 0.05, 0.03, 0.57, so ``b* = 3`` and ``m* = 15``.

    Edge cases: no positive rise (a curve that is 0 everywhere, or only falls) gives ``b*``
    and ``m*`` None with a reason; no eligible bin gives None with a reason; no step at all
    gives an empty curve with a reason.

    :param items: The episodes whose steps are binned by previous-map load.
    :param width: ``w``, the labels per load bin (the paper's 5).
    :param min_steps: Steps a bin needs to be eligible for the inflection.
    :returns: A :class:`MillerCurve`: ``ML(b)`` and steps per bin, ``b*`` and ``m*`` or a reason.
    """
    check_positive_int("width", width)
    check_positive_int("min_steps", min_steps)
    kept, _ = split_errored(items)
    loads = np.array([x for m in kept for x in m.miller_loads], dtype=np.int64)
    forgets = np.array([x for m in kept for x in m.miller_forgets], dtype=bool)
    if not len(loads):
        return MillerCurve(width=width, reason="no step with a non-empty map")
    b = -(-loads // width)
    steps = np.bincount(b)
    events = np.bincount(b[forgets], minlength=len(steps))
    bins = np.flatnonzero(steps)
    probs = events[bins] / steps[bins]
    eligible = [(0, 0.0)] + [
        (int(b), float(p)) for b, p in zip(bins, probs, strict=True) if steps[b] >= min_steps
    ]
    rises = [(p - p_prev, b_now) for (_, p_prev), (b_now, p) in pairwise(eligible)]
    best = max(rises, key=lambda r: r[0], default=(0.0, 0))
    b_star = best[1] if best[0] > 0 else None
    reason = None
    if b_star is None:
        reason = "no rise between consecutive load bins (from ML(0) = 0): no inflection"
        if len(eligible) < 2:
            reason = f"no load bin with >= {min_steps} steps: no inflection"
    return MillerCurve(
        width=width,
        bins=tuple(bins.tolist()),
        probabilities=tuple(probs.tolist()),
        steps=tuple(steps[bins].tolist()),
        events=tuple(events[bins].tolist()),
        b_star=b_star,
        m_star=None if b_star is None else b_star * width,
        reason=reason,
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
    """SIR per episode (see :func:`sir_score`), with undefined episodes counted by reason.

    :param items: The episodes, each scored by :func:`sir_score`.
    :returns: A :class:`SpatialIdentityResolution`: the defined values and the count per reason.
    """
    kept, excluded = split_errored(items)
    values = tuple(m.sir for m in kept if m.sir is not None)
    undefined = Counter(m.reasons.get("sir", "undefined") for m in kept if m.sir is None)
    mean = statistics.fmean(values) if values else None
    return SpatialIdentityResolution(values, mean, dict(undefined), excluded)


def anova_conditions(items: Iterable[EpisodeLike]) -> Anova:
    """One-way ANOVA of per-episode memory strength across conditions (statsmodels).

    Each episode's EFC is ``sum t_j / d`` over its objects' first spells. Episodes with no
    spell (None) or no forgetting event (``inf``) carry no finite strength and are left out
    (the ``groups`` sizes show what was used). See :func:`anova_groups` for degenerate cases.

    :param items: The episodes, grouped by their spec's condition.
    :returns: The :class:`Anova` of :func:`anova_groups` over the finite strengths.
    """
    kept, _ = split_errored(items)
    groups: dict[str, list[float]] = {}
    for m in kept:
        strength = m.memory_strength
        if strength is not None and math.isfinite(strength):
            groups.setdefault(m.spec.condition, []).append(strength)
    return anova_groups(groups)


@dataclass(frozen=True)
class FocalRow:
    """Chosen-room letters of a group of episodes."""

    n: int
    counts: dict[str, int]
    """Letter (``C``, ``O``, ``K``, ``E``, ``X``) -> episodes."""
    fractions: dict[str, float]
    """Letter -> share of ``n`` in [0, 1] (all 0.0 when ``n = 0``)."""
    named_other: int = 0
    """Episodes of ``X`` that ended with ``Term(r)``, ``r`` outside the four rooms."""
    no_term: int = 0
    """Episodes of ``X`` that never terminated (the action budget ran out)."""
    chose_spawn: int = 0
    """Episodes that chose the room they spawned in (Appendix F's recency/proximity bias)."""

    @property
    def spawn_share(self) -> float | None:
        """``chose_spawn / n`` in [0, 1] (Appendix F: 50.6 %, chance 25 %); None when n = 0."""
        return self.chose_spawn / self.n if self.n else None


def _row(items: Sequence[EpisodeMetrics]) -> FocalRow:
    counts = Counter(m.chosen_letter for m in items)
    n = len(items)
    named_other = sum(m.chosen_letter == OTHER_LETTER and m.status == "terminated" for m in items)
    return FocalRow(
        n,
        {c: counts[c] for c in FOCAL_COLUMNS},
        {c: (counts[c] / n if n else 0.0) for c in FOCAL_COLUMNS},
        named_other=named_other,
        no_term=counts[OTHER_LETTER] - named_other,
        chose_spawn=sum(
            m.chosen_letter == room_letter(SLUG_ROOMS.get(m.spec.spawn, m.spec.spawn))
            for m in items
        ),
    )


@dataclass(frozen=True)
class FocalDistribution:
    """The paper's focal-point table: chosen-room distribution per spawn room."""

    by_spawn: dict[str, FocalRow]
    """Spawn slug -> row, in the order spawns first appear."""
    overall: FocalRow
    excluded: int
    """Errored episodes left out."""


def focal_distribution(items: Iterable[EpisodeLike]) -> FocalDistribution:
    """Chosen-room distribution (C/O/K/E/X) by spawn room, as fractions in [0, 1].

    ``X`` is anything but the four rooms; each row also counts its two kinds apart
    (``named_other``: a ``Term`` naming another room; ``no_term``: the budget ran out) and the
    episodes that chose their spawn room (Appendix F's share; an ``X`` never counts).
    Errored episodes are excluded and counted. No episodes: empty ``by_spawn``, ``n = 0``.

    :param items: The episodes, grouped by spawn room.
    :returns: A :class:`FocalDistribution`: a :class:`FocalRow` per spawn room and overall.
    """
    kept, excluded = split_errored(items)
    by_spawn: dict[str, list[EpisodeMetrics]] = {}
    for m in kept:
        by_spawn.setdefault(m.spec.spawn, []).append(m)
    rows = {spawn: _row(group) for spawn, group in by_spawn.items()}
    return FocalDistribution(rows, _row(kept), excluded)


@dataclass(frozen=True)
class Consensus:
    """Share of episodes choosing the modal room."""

    letter: str | None
    """Modal room letter among C/O/K/E (None when no episode chose a room)."""
    share: float | None
    """Episodes choosing it / all non-errored episodes, in [0, 1]."""
    n: int


def consensus(items: Iterable[EpisodeLike]) -> Consensus:
    """Focal-point consensus: the share of the modal chosen room across every spawn.

    The mode is taken among the four rooms (``X`` is a failure to choose, never a consensus);
    ties go to the first letter in C, O, K, E order. The denominator is every non-errored
    episode, ``X`` included. No episode: share None; no room ever chosen: letter None, share 0.

    :param items: The episodes whose chosen rooms are pooled over every spawn.
    :returns: A :class:`Consensus`: the modal room's letter and share, and ``n``.
    """
    kept, _ = split_errored(items)
    if not kept:
        return Consensus(None, None, 0)
    counts = Counter(m.chosen_letter for m in kept if m.chosen_letter != OTHER_LETTER)
    if not counts:
        return Consensus(None, 0.0, len(kept))
    letter = max((c for c in FOCAL_COLUMNS if c in counts), key=lambda c: counts[c])
    return Consensus(letter, counts[letter] / len(kept), len(kept))


@dataclass(frozen=True, kw_only=True)
class FPSGSummary:
    """One row of the paper's FPSG table (Appendix G)."""

    runs: int
    """Non-errored episodes."""
    never_visited: float | None
    """Share of episodes with a chosen room that chose a room never entered, in [0, 1]."""
    any_bias: float | None
    """Share of episodes with a chosen room whose final map holds none of its objects."""
    local_mean: float | None
    local_sd: float | None
    global_mean: float | None
    global_sd: float | None
    excluded: int
    local_mean_ex_doorways: float | None = None
    """``local_mean`` with doorways left out of ``O_F`` (our variant)."""
    global_mean_ex_doorways: float | None = None
    """``global_mean`` with doorways left out of ``O_F``."""


def _mean_sd(kept: list[EpisodeMetrics], name: str) -> tuple[float | None, float | None]:
    """Mean and sample standard deviation of the score ``name`` where it is defined."""
    values = [v for m in kept if (v := getattr(m, name)) is not None]
    if not values:
        return None, None
    mean = statistics.fmean(values)
    if len(values) < 2:
        return mean, None
    var = math.fsum((v - mean) ** 2 for v in values) / (len(values) - 1)
    return mean, math.sqrt(var)


def fpsg(items: Iterable[EpisodeLike]) -> FPSGSummary:
    r"""Focal-Point Spatial Grounding summary (Eq. FSPG and its local variant, Appendix B).

    .. math::
        \overline{FPSG} = \frac{1}{N}\sum_i \frac{|\hat{M}_F \cap \mathcal{O}_F|}{|N_{base}|},
        \qquad
        \overline{FPSG}_{local} = \frac{1}{N}\sum_i
            \frac{|\hat{M}_F \cap \mathcal{O}_F|}{|\mathcal{O}_F|}

    ``O_F`` holds every object of the chosen room, doorways included (the paper's definition);
    ``*_ex_doorways`` are the means of our doorway-free variant (see :func:`grounding_scores`).
    Means and sample standard deviations over episodes where each is defined; Never-Visited
    and Any-Bias are shares of episodes with a chosen room (Any-Bias: the final map holds no
    object of the chosen room). No such episode: None. One episode: sd None.

    :param items: The episodes, each scored by :func:`grounding_scores`.
    :returns: An :class:`FPSGSummary`: means and sds of every variant, Never-Visited and Any-Bias.
    """
    kept, excluded = split_errored(items)
    local_mean, local_sd = _mean_sd(kept, "fpsg_local")
    global_mean, global_sd = _mean_sd(kept, "fpsg_global")
    return FPSGSummary(
        runs=len(kept),
        never_visited=_share([m.never_visited for m in kept]),
        any_bias=_share([m.any_bias for m in kept]),
        local_mean=local_mean,
        local_sd=local_sd,
        global_mean=global_mean,
        global_sd=global_sd,
        excluded=excluded,
        local_mean_ex_doorways=_mean_sd(kept, "fpsg_local_ex_doorways")[0],
        global_mean_ex_doorways=_mean_sd(kept, "fpsg_global_ex_doorways")[0],
    )


def _share(flags: Sequence[bool | None]) -> float | None:
    """The share of True among the flags that are not None (None without any)."""
    known = [f for f in flags if f is not None]
    return sum(known) / len(known) if known else None
