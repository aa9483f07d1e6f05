"""The per-episode result: every EMRD score of one trajectory, as plain data.

:class:`EpisodeMetrics` is what the results store may save beside each trajectory and what
every aggregate and gate reads, so an episode's steps are matched once however many metrics
are asked for. Aggregates accept trajectories or ``EpisodeMetrics`` interchangeably.
"""

from __future__ import annotations

import math
from collections import Counter
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from functools import cached_property
from typing import Any, Final

from pytest_emrd._serde import from_versioned_dict, to_dict
from pytest_emrd.metrics._scores import (
    aec_score,
    grounding_scores,
    hallucination_score,
    positional_accuracy_score,
    precision_score,
    serial_position_bins,
    sir_score,
    te_score,
)
from pytest_emrd.metrics._tracking import Spell, first_spells, track_episode
from pytest_emrd.rooms import room_letter
from pytest_emrd.trajectory import CATEGORIES, EpisodeSpec, Trajectory

SCHEMA_VERSION: Final = 2


@dataclass(frozen=True)
class EpisodeMetrics:
    """Every per-episode EMRD score of one trajectory. Fractions are in [0, 1]."""

    spec: EpisodeSpec
    status: str
    """Trajectory status: ``terminated``, ``budget`` or ``errored``."""
    errored: bool
    """Errored episodes carry no scores; aggregates exclude and count them."""
    steps: int
    """Decision cycles recorded."""
    parse_failures: int
    """Steps whose reply could not be read."""
    te: int | None
    """Temporal Efficiency: actions before ``Term`` or the budget (Eq. TE)."""
    aec: float | None
    """Absolute Environment Coverage of the terminal map (Eq. AEC)."""
    pa: float | None
    """Positional Accuracy of the terminal map (Eq. PA)."""
    matched: int
    """``|K|``: terminal-map entries matched to ground truth."""
    g_base: int
    """``|G_base|``: objects discoverable under the unperturbed baseline."""
    unmatched: int
    """``|U|``: recognised terminal-map entries left without an object (PA's charge)."""
    precision: float | None
    """Map precision: share of the terminal map's entries standing for a real object."""
    hallucination_rate: float | None
    """Share of the terminal map's entries of a type the office does not hold."""
    tbs: tuple[float, ...]
    """Temporal Belief Stability ``TBS(t)`` for ``t = 1..steps`` (Eq. TBS)."""
    fpsg_local: float | None
    fpsg_global: float | None
    never_visited: bool | None
    """The chosen room is one the agent never stood in (None: no chosen room)."""
    any_bias: bool | None
    """The final map holds no confirmed object of the chosen room (None: no chosen room)."""
    chosen_letter: str
    """Focal-point column: ``C``, ``O``, ``K``, ``E`` or ``X`` (anything else, incl. no Term)."""
    sir: float | None
    """Spatial Identity Resolution (None when no room was re-entered; see ``reasons``)."""
    spells: tuple[Spell, ...]
    """Every out-of-view spell of every mapped object, in start order."""
    mapped_by_category: dict[str, int]
    """Objects ever held in the map, per memory category (coverage numerator ``C_X``)."""
    objects_by_category: dict[str, int]
    """Ground-truth objects per memory category (coverage denominator ``C_X``)."""
    serial_position: tuple[float | None, float | None, float | None]
    """Mean TTF of the Early / Middle / Late discovery thirds (Eq. SPE)."""
    miller_loads: tuple[int, ...]
    """Map size ``m = |M_{t-1}|`` for each step ``t >= 2`` with ``m >= 1``."""
    miller_forgets: tuple[bool, ...]
    """Forgetting indicator of those steps (Eq. MillerLaw)."""
    rationale: str | None = None
    """The terminal reasoning, for representative-reasoning analysis."""
    reasons: dict[str, str] = field(default_factory=dict)
    """Metric name -> why it is None (or, for ``memory_strength``, unbounded)."""
    fpsg_local_ex_doorways: float | None = None
    """``fpsg_local`` with doorways left out of ``O_F`` (our variant, reported beside)."""
    fpsg_global_ex_doorways: float | None = None
    """``fpsg_global`` with doorways left out of ``O_F``."""
    schema_version: int = SCHEMA_VERSION

    @cached_property
    def ttf_spells(self) -> tuple[Spell, ...]:
        """The first spell of each object: its time-to-forget, in discovery order."""
        return first_spells(self.spells)

    @property
    def forget_events(self) -> int:
        """``d``: uncensored forgetting events among ``ttf_spells``."""
        return sum(s.forgotten for s in self.ttf_spells)

    @property
    def retained_steps(self) -> int:
        """``sum t_j`` over ``ttf_spells`` (events and censored alike)."""
        return sum(s.duration for s in self.ttf_spells)

    @property
    def memory_strength(self) -> float | None:
        """Per-episode EFC ``sum t_j / d`` (Eq. SMLE): ``inf`` when ``d = 0`` with spells,
        None without spells or for an errored episode."""
        if self.errored or not self.spells:
            return None
        d = self.forget_events
        return self.retained_steps / d if d else math.inf

    def to_dict(self) -> dict[str, Any]:
        return to_dict(self)

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> EpisodeMetrics:
        return from_versioned_dict(
            cls,
            data,
            version=SCHEMA_VERSION,
            what="episode metrics",
            remedy="recompute them from the trajectory with episode_metrics().",
        )


def episode_metrics(traj: Trajectory) -> EpisodeMetrics:
    """Compute every per-episode score of ``traj`` (one pass over its steps)."""
    objects_by_category = dict(Counter(o.category for o in traj.ground_truth.objects))
    g_base = len(traj.ground_truth.discoverable_ids)
    if traj.status == "errored":
        return _errored(traj, objects_by_category, g_base)
    track = track_episode(traj)
    final = track.final
    reasons: dict[str, str] = {}
    aec = aec_score(final, len(traj.ground_truth.objects))
    pa = positional_accuracy_score(final, g_base)
    if aec is None:
        reasons["aec"] = "the ground truth lists no object (|E| = 0)"
    if pa is None:
        reasons["pa"] = "no object is discoverable under the baseline (|G_base| = 0)"
    precision = precision_score(final)
    hallucination = hallucination_score(final)
    if precision is None:
        reasons["precision"] = reasons["hallucination_rate"] = "the terminal map is empty"
    if g_base == 0:
        reasons["tbs"] = "no object is discoverable under the baseline (|G_base| = 0)"
    grounding = grounding_scores(traj, final)
    reasons.update(grounding.reasons)
    sir, why = sir_score(traj, track, aec)
    if sir is None:
        reasons["sir"] = why
    if not track.spells:
        reasons["memory_strength"] = "no mapped object ever left view"
    elif not any(s.forgotten for s in first_spells(track.spells)):
        reasons["memory_strength"] = "no forgetting event: memory strength is unbounded"
    category = {o.object_id: o.category for o in traj.ground_truth.objects}
    ttf = {s.object_id: float(s.duration) for s in first_spells(track.spells)}
    by_rank = sorted(track.discovery, key=track.discovery.__getitem__)
    return EpisodeMetrics(
        spec=traj.spec,
        status=traj.status,
        errored=False,
        steps=len(traj.steps),
        parse_failures=sum(s.parse_error is not None for s in traj.steps),
        te=te_score(traj),
        aec=aec,
        pa=pa,
        matched=len(final.pairs),
        g_base=g_base,
        unmatched=len(final.unmatched),
        precision=precision,
        hallucination_rate=hallucination,
        tbs=track.tbs,
        fpsg_local=grounding.fpsg_local,
        fpsg_global=grounding.fpsg_global,
        never_visited=grounding.never_visited,
        any_bias=grounding.any_bias,
        chosen_letter=room_letter(traj.chosen_room),
        sir=sir,
        spells=track.spells,
        mapped_by_category=dict(Counter(category[o] for o in track.discovery)),
        objects_by_category=objects_by_category,
        serial_position=serial_position_bins([ttf.get(o) for o in by_rank]),
        miller_loads=track.miller_loads,
        miller_forgets=track.miller_forgets,
        rationale=traj.rationale,
        reasons=reasons,
        fpsg_local_ex_doorways=grounding.fpsg_local_ex_doorways,
        fpsg_global_ex_doorways=grounding.fpsg_global_ex_doorways,
    )


def _errored(traj: Trajectory, objects_by_category: dict[str, int], g_base: int) -> EpisodeMetrics:
    why = f"episode errored: {traj.error or 'no cause recorded'}"
    names = (
        "te",
        "aec",
        "pa",
        "precision",
        "hallucination_rate",
        "tbs",
        "fpsg_local",
        "fpsg_global",
        "never_visited",
        "any_bias",
        "sir",
        "memory_strength",
    )
    return EpisodeMetrics(
        spec=traj.spec, status=traj.status, errored=True, steps=len(traj.steps),
        parse_failures=sum(s.parse_error is not None for s in traj.steps), te=None, aec=None,
        pa=None, matched=0, g_base=g_base, unmatched=0, precision=None,
        hallucination_rate=None, tbs=(), fpsg_local=None, fpsg_global=None,
        never_visited=None, any_bias=None, chosen_letter=room_letter(None), sir=None, spells=(),
        mapped_by_category={}, objects_by_category=objects_by_category,
        serial_position=(None, None, None), miller_loads=(), miller_forgets=(),
        rationale=traj.rationale, reasons=dict.fromkeys(names, why),
    )  # fmt: skip


EpisodeLike = Trajectory | EpisodeMetrics


def as_episode_metrics(items: Iterable[EpisodeLike]) -> list[EpisodeMetrics]:
    """Episode metrics of each item: computed for a trajectory, passed through otherwise."""
    return [i if isinstance(i, EpisodeMetrics) else episode_metrics(i) for i in items]


def split_errored(
    items: Iterable[EpisodeLike],
) -> tuple[list[EpisodeMetrics], int]:
    """The non-errored episode metrics, and how many errored episodes were excluded."""
    all_metrics = as_episode_metrics(items)
    kept = [m for m in all_metrics if not m.errored]
    return kept, len(all_metrics) - len(kept)


def categories_of(metrics: Sequence[EpisodeMetrics]) -> list[str]:
    """Memory categories present, the standard three first, then any other, sorted."""
    seen = {c for m in metrics for c in m.objects_by_category}
    return [c for c in CATEGORIES if c in seen] + sorted(seen - set(CATEGORIES))
