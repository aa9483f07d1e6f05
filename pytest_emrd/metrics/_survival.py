"""Coverage-anchored Kaplan-Meier and the Ebbinghaus exponential fit, on raw spell data.

Inputs are durations (steps an object was retained out of view) with event flags (True: the
object was dropped; False: right-censored, i.e. seen again or the episode ended while still
held). Censoring is assumed non-informative, as Kaplan-Meier and the exponential MLE require.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from pytest_emrd.errors import ConfigError, check_range


def _spell_arrays(
    durations: Sequence[float] | np.ndarray, observed: Sequence[bool] | np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    t = np.asarray(durations, dtype=float).reshape(-1)
    e = np.asarray(observed, dtype=bool).reshape(-1)
    if t.shape != e.shape:
        raise ConfigError(
            f"durations (n={t.size}) and observed (n={e.size}) must have the same length."
        )
    if not np.all(np.isfinite(t)) or np.any(t <= 0):
        raise ConfigError(
            "durations must be finite and > 0 (a spell lasts at least one step); "
            "drop or fix the offending spells."
        )
    return t, e


def efc(
    durations: Sequence[float] | np.ndarray, observed: Sequence[bool] | np.ndarray
) -> float | None:
    r"""Ebbinghaus memory strength: the censored exponential MLE (Eq. SMLE).

    .. math::
        \overline{EFC} = \frac{\sum_{j=1}^{n} t_j}{d}

    ``t_j`` runs over every spell, forgotten or censored; ``d`` counts the forgetting events.
    It estimates the mean retention time (steps) of an exponential forgetting process under
    non-informative right-censoring. Edge cases: no spell gives None; spells but no event
    gives ``inf`` (memory strength unbounded: nothing was ever forgotten).
    """
    t, e = _spell_arrays(durations, observed)
    if t.size == 0:
        return None
    d = int(e.sum())
    return math.fsum(t.tolist()) / d if d else math.inf


@dataclass(frozen=True)
class AnchoredKM:
    """A coverage-anchored Kaplan-Meier curve ``S(t) = C * prod (1 - d/n)``."""

    coverage: float
    """``C_X``: the anchor, ``S(0)``."""
    times: tuple[float, ...]
    """``0`` then every distinct spell duration, ascending."""
    survival: tuple[float, ...]
    """Anchored survival at each time (``survival[0] == coverage``)."""
    at_risk: tuple[int, ...]
    """``n_tau``: spells with duration ``>= tau`` (``at_risk[0]`` is every spell)."""
    events: tuple[int, ...]
    """``d_tau``: forgetting events at ``tau`` (``events[0] == 0``)."""

    @property
    def n(self) -> int:
        return self.at_risk[0]

    def at(self, t: float) -> float:
        """Anchored survival at time ``t`` (right-continuous step function, ``S(t<0) = C``)."""
        i = int(np.searchsorted(np.asarray(self.times), t, side="right")) - 1
        return self.survival[max(i, 0)]


def anchored_km(
    durations: Sequence[float] | np.ndarray,
    observed: Sequence[bool] | np.ndarray,
    *,
    coverage: float,
) -> AnchoredKM:
    r"""Coverage-anchored Kaplan-Meier estimate (Appendix B).

    .. math::
        \hat{S}_{\mathcal{X}}(t) = C_{\mathcal{X}} \prod_{\tau \le t}
            \left(1 - \frac{d_\tau}{n_\tau}\right)

    The absolute probability that an object of the set is both discovered and still held
    ``t`` steps after leaving view. ``n_tau`` counts spells still at risk at ``tau``
    (duration ``>= tau``: a spell censored at ``tau`` is at risk at ``tau``, the convention
    of lifelines); ``d_tau`` the events at ``tau``. Starts at ``C`` and never increases.
    Edge cases: no spells gives the single point ``(0, C)``; no events gives a flat curve at
    ``C``; ties are counted together. ``coverage`` must lie in [0, 1]; durations must be
    finite and > 0.
    """
    check_range("coverage", coverage, 0.0, 1.0)
    t, e = _spell_arrays(durations, observed)
    times, inverse = np.unique(t, return_inverse=True)
    deaths = np.bincount(inverse, weights=e.astype(float), minlength=len(times))
    leaving = np.bincount(inverse, minlength=len(times))
    at_risk = len(t) - np.concatenate(([0], np.cumsum(leaving)[:-1]))
    with np.errstate(divide="ignore", invalid="ignore"):
        factors = np.where(at_risk > 0, 1.0 - deaths / at_risk, 1.0)
    survival = coverage * np.cumprod(factors)
    return AnchoredKM(
        coverage=float(coverage),
        times=(0.0, *times.tolist()),
        survival=(float(coverage), *survival.tolist()),
        at_risk=(len(t), *at_risk.astype(int).tolist()),
        events=(0, *deaths.astype(int).tolist()),
    )


@dataclass(frozen=True)
class EbbinghausFit:
    """The Ebbinghaus curve ``R(t) = C exp(-t / EFC)`` and its fit to the anchored KM."""

    coverage: float
    """``C_X``."""
    efc: float | None
    """Memory strength (Eq. SMLE): None without spells, ``inf`` without events."""
    r2: float | None
    """Coefficient of determination of ``R`` against the anchored KM (may be negative)."""
    n_spells: int
    n_events: int
    reason: str | None = None


def ebbinghaus_fit(
    durations: Sequence[float] | np.ndarray,
    observed: Sequence[bool] | np.ndarray,
    *,
    coverage: float,
) -> EbbinghausFit:
    r"""Memory strength (Eq. SMLE) and goodness of fit of Eq. EbbinghausFC against KM.

    .. math::
        R_{\mathcal{X}}(\delta) = C_{\mathcal{X}} \exp(-\delta / \overline{EFC}_{\mathcal{X}}),
        \qquad
        R^2 = 1 - \frac{\sum_t (\hat{S}(t) - R(t))^2}{\sum_t (\hat{S}(t) - \bar{S})^2}

    ``t`` runs over the KM's time points after 0 (every distinct spell duration). ``EFC`` is
    the MLE, not a least-squares fit, so ``R^2`` is a diagnostic: negative when a flat mean
    predicts the KM curve better than the exponential (abrupt, non-exponential forgetting).
    Edge cases: no spells -> efc and r2 None; no events -> efc ``inf`` (reason given) and the
    curve is flat at ``C``; a KM curve with no variation (one time point, or flat) -> r2 None
    with a reason.
    """
    t, e = _spell_arrays(durations, observed)
    strength = efc(t, e)
    n_events = int(e.sum())
    if strength is None:
        return EbbinghausFit(coverage, None, None, 0, 0, "no spells: nothing left view mapped")
    km = anchored_km(t, e, coverage=coverage)
    grid = np.asarray(km.times[1:])
    s_hat = np.asarray(km.survival[1:])
    reason = None if n_events else "no forgetting event: memory strength is unbounded"
    ss_tot = float(np.sum((s_hat - s_hat.mean()) ** 2)) if len(s_hat) else 0.0
    if ss_tot <= 1e-15:
        why = "the Kaplan-Meier curve does not vary: R^2 is undefined"
        return EbbinghausFit(coverage, strength, None, len(t), n_events, reason or why)
    model = coverage * np.exp(-grid / strength)
    r2 = 1.0 - float(np.sum((s_hat - model) ** 2)) / ss_tot
    return EbbinghausFit(coverage, strength, r2, len(t), n_events, reason)
