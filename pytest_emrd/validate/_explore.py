"""Explore rows: the scout's coverage reaches what is discoverable, and low light costs
coverage and time for the same agent in the same offices (paired episodes)."""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Final

from pytest_emrd.metrics import GATE_METRICS, Estimate, as_episode_metrics
from pytest_emrd.validate._check import Check, Episode, fmt, judged

#: Baseline AEC of the perfect scout may fall short of ``|G_base| / |E|`` by at most this.
COVERAGE_GAP: Final = 0.05


def _value(estimate: Estimate) -> float:
    return estimate.value if estimate.value is not None else math.nan


def _ci(estimate: Estimate) -> str:
    return f"95 % CI {fmt(estimate.ci_low, 3)}-{fmt(estimate.ci_high, 3)}"


def exploration_checks(baseline: Sequence[Episode], low_light: Sequence[Episode]) -> list[Check]:
    """AEC close to the discoverable fraction; low_light lowers AEC and raises TE."""
    aec, te = GATE_METRICS["aec"], GATE_METRICS["te"]
    base_aec, dark_aec = aec.compute(baseline), aec.compute(low_light)
    base_te, dark_te = te.compute(baseline), te.compute(low_light)
    fractions = [
        m.g_base / total
        for m in as_episode_metrics(baseline)
        if (total := sum(m.objects_by_category.values()))
    ]
    discoverable = math.fsum(fractions) / len(fractions) if fractions else math.nan
    gap = abs(discoverable - _value(base_aec))
    return [
        Check("Explore", "AEC vs discoverable fraction, scout", f"{fmt(discoverable, 3)}",
              f"{fmt(base_aec.value, 3)}", f"within {COVERAGE_GAP}",
              judged(gap <= COVERAGE_GAP),
              f"{base_aec.n} episodes; discoverable = mean |G_base|/|E|; {_ci(base_aec)}",
              {"aec": base_aec.value, "discoverable": discoverable}),
        Check("Explore", "AEC, scout: low_light vs baseline", "lower",
              f"{fmt(dark_aec.value, 3)} vs {fmt(base_aec.value, 3)}", "strictly lower",
              judged(_value(dark_aec) < _value(base_aec)),
              f"{dark_aec.n} paired episodes; low_light {_ci(dark_aec)}",
              {"aec_low_light": dark_aec.value, "aec_baseline": base_aec.value}),
        Check("Explore", "TE, scout: low_light vs baseline", "higher",
              f"{fmt(dark_te.value, 1)} vs {fmt(base_te.value, 1)} steps", "strictly higher",
              judged(_value(dark_te) > _value(base_te)),
              f"{dark_te.n} paired episodes; low_light {_ci(dark_te)}",
              {"te_low_light": dark_te.value, "te_baseline": base_te.value}),
    ]  # fmt: skip
