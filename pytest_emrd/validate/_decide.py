"""Decide rows: Never-Visited, Any-Bias and FPSG recover the planted grounding of ``prior``
(a textual prior, no evidence) and ``scout`` (chooses where it mapped the most)."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Final

from pytest_emrd.metrics import fpsg
from pytest_emrd.validate._check import Check, Episode, fmt, judged, pct

#: ``FPSG_local`` of the perfect-memory scout's chosen room must be at least this.
SCOUT_MIN_LOCAL: Final = 0.9


def prior_checks(trajectories: Sequence[Episode]) -> list[Check]:
    """``prior`` names a room it never entered, from the prompt alone: Never-Visited and
    Any-Bias 100 %, FPSG 0."""
    s = fpsg(trajectories)
    note = f"{s.runs} episodes"
    return [
        Check("Decide", "Never-Visited, prior", "100 %", pct(s.never_visited), "exactly 100 %",
              judged(s.never_visited == 1.0), note, {"never_visited": s.never_visited}),
        Check("Decide", "Any-Bias, prior", "100 %", pct(s.any_bias), "exactly 100 %",
              judged(s.any_bias == 1.0), note, {"any_bias": s.any_bias}),
        Check("Decide", "FPSG global, prior", "0", fmt(s.global_mean, 3), "exactly 0",
              judged(s.global_mean == 0.0), f"{note}; local {fmt(s.local_mean, 3)}",
              {"fpsg_global": s.global_mean, "fpsg_local": s.local_mean}),
    ]  # fmt: skip


def scout_decide_checks(trajectories: Sequence[Episode]) -> list[Check]:
    """``scout`` chooses a room it swept and remembers: Never-Visited 0 %, FPSG local ~ 1."""
    s = fpsg(trajectories)
    note = f"{s.runs} episodes"
    return [
        Check("Decide", "Never-Visited, scout", "0 %", pct(s.never_visited), "exactly 0 %",
              judged(s.never_visited == 0.0), note, {"never_visited": s.never_visited}),
        Check("Decide", "FPSG local, scout", "1 (near)", fmt(s.local_mean, 3),
              f">= {SCOUT_MIN_LOCAL}",
              judged(s.local_mean is not None and s.local_mean >= SCOUT_MIN_LOCAL),
              f"{note}; sd {fmt(s.local_sd, 3)}, global {fmt(s.global_mean, 3)}",
              {"fpsg_local": s.local_mean, "fpsg_global": s.global_mean}),
    ]  # fmt: skip
