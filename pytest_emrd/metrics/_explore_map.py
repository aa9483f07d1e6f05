"""Explore- and Map-phase aggregates: per-episode positional accuracy and the TBS curve."""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np

from pytest_emrd.metrics._episode import EpisodeLike, as_episode_metrics, split_errored


def positional_accuracy(items: Iterable[EpisodeLike]) -> tuple[float | None, ...]:
    """Positional Accuracy (Eq. PA) of each episode, in input order.

    None for an errored episode or when ``|G_base| = 0`` (see
    :func:`positional_accuracy_score` for the formula and every edge case).
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
    """
    kept, errored = split_errored(items)
    usable = [m for m in kept if m.tbs]
    excluded = errored + len(kept) - len(usable)
    horizon = t_max if t_max is not None else max((m.spec.max_steps for m in usable), default=0)
    if not usable or horizon < 1:
        return TBSCurve((), (), (), 0, excluded)
    grid = np.empty((len(usable), horizon))
    for i, m in enumerate(usable):
        series = np.asarray(m.tbs[:horizon], dtype=float)
        grid[i, : len(series)] = series
        grid[i, len(series) :] = series[-1]
    return TBSCurve(
        tuple(range(1, horizon + 1)),
        tuple(grid.mean(axis=0).tolist()),
        tuple(grid.std(axis=0).tolist()),
        len(usable),
        excluded,
    )
