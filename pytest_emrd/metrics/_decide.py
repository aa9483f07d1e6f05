"""Decide-phase aggregates: focal-point distribution by spawn, consensus, FPSG summary."""

from __future__ import annotations

import math
from collections import Counter
from collections.abc import Iterable, Sequence
from dataclasses import dataclass

from pytest_emrd.metrics._episode import EpisodeLike, EpisodeMetrics, split_errored
from pytest_emrd.rooms import FOCAL_COLUMNS, OTHER_LETTER, ROOM_LETTERS, SLUG_ROOMS


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
    letters = [m.chosen_letter for m in items]
    counts = Counter(letters)
    n = len(letters)
    other = [m for m in items if m.chosen_letter == OTHER_LETTER]
    return FocalRow(
        n,
        {c: counts.get(c, 0) for c in FOCAL_COLUMNS},
        {c: (counts.get(c, 0) / n if n else 0.0) for c in FOCAL_COLUMNS},
        named_other=sum(m.status == "terminated" for m in other),
        no_term=sum(m.status != "terminated" for m in other),
        chose_spawn=sum(m.chosen_letter == _spawn_letter(m.spec.spawn) for m in items),
    )


def _spawn_letter(spawn: str) -> str:
    return ROOM_LETTERS.get(SLUG_ROOMS.get(spawn, spawn), OTHER_LETTER)


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
    """
    kept, excluded = split_errored(items)
    by_spawn: dict[str, list[EpisodeMetrics]] = {}
    for m in kept:
        by_spawn.setdefault(m.spec.spawn, []).append(m)
    return FocalDistribution(
        {spawn: _row(group) for spawn, group in by_spawn.items()},
        _row(kept),
        excluded,
    )


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
    """
    kept, _ = split_errored(items)
    if not kept:
        return Consensus(None, None, 0)
    counts = Counter(m.chosen_letter for m in kept if m.chosen_letter != OTHER_LETTER)
    if not counts:
        return Consensus(None, 0.0, len(kept))
    letter = max((c for c in FOCAL_COLUMNS if c in counts), key=lambda c: counts[c])
    return Consensus(letter, counts[letter] / len(kept), len(kept))


@dataclass(frozen=True)
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


def _mean_sd(values: Sequence[float]) -> tuple[float | None, float | None]:
    if not values:
        return None, None
    mean = math.fsum(values) / len(values)
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
    """
    kept, excluded = split_errored(items)
    local = [m.fpsg_local for m in kept if m.fpsg_local is not None]
    glob = [m.fpsg_global for m in kept if m.fpsg_global is not None]
    never = [m.never_visited for m in kept if m.never_visited is not None]
    bias = [m.any_bias for m in kept if m.any_bias is not None]
    lm, ls = _mean_sd(local)
    gm, gs = _mean_sd(glob)
    lx, _ = _mean_sd([v for m in kept if (v := m.fpsg_local_ex_doorways) is not None])
    gx, _ = _mean_sd([v for m in kept if (v := m.fpsg_global_ex_doorways) is not None])
    return FPSGSummary(
        len(kept),
        sum(never) / len(never) if never else None,
        sum(bias) / len(bias) if bias else None,
        lm,
        ls,
        gm,
        gs,
        excluded,
        lx,
        gx,
    )
