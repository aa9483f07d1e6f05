"""A starter ``thresholds.yaml`` from runs (``emrd thresholds``; pure text from estimates)."""

from __future__ import annotations

import math
from collections import defaultdict
from collections.abc import Iterable, Mapping, Sequence
from typing import TYPE_CHECKING, Any, Final

from pytest_emrd.gate._verdict import format_number

if TYPE_CHECKING:
    from pytest_emrd.metrics import GateMetric

#: The metrics a starter file gates (those the registry holds), as the shipped file does.
STARTER_METRICS: Final = (
    "aec",
    "precision",
    "pa",
    "ungrounded_rate",
    "never_visited",
    "parse_failure_rate",
    "errored_rate",
)
#: How far past its CI end a starter bound sits (a fraction: 5 points of coverage).
MARGIN: Final = 0.05


def starter_thresholds(
    episodes: Sequence[Any], metrics: Mapping[str, GateMetric], *, command: str
) -> str:
    """A commented thresholds file: per model and condition (and layouts), a bound per
    :data:`STARTER_METRICS` metric at its bootstrap 95 % CI end moved :data:`MARGIN` further
    (the lower end for higher-is-better, the upper for lower-is-better; the loosest over
    prompt variants), rounded outward to 2 decimals and kept in [0, 1]: ``episodes``
    (``EpisodeMetrics``) pass it and a clear regression fails. ``command`` made it.

    :param episodes: :class:`EpisodeMetrics` of a run the file should pass.
    :param metrics: Metric name -> :class:`GateMetric`, for each bound's CI.
    :param command: The command line quoted in the file's header.
    :returns: The thresholds YAML text.
    """
    cells: dict[tuple[str, str], dict[str, list[Any]]] = defaultdict(lambda: defaultdict(list))
    for m in episodes:
        s = m.spec
        key = s.condition if s.layouts == "paper" else f"{s.condition}@{s.layouts}"
        cells[(s.model, key)][s.variant].append(m)
    names = [n for n in STARTER_METRICS if n in metrics]
    lines = [
        f"# Starter gates written by `{command}` from {len(episodes)} episodes.",
        f"# Each bound is the run's bootstrap 95% CI end moved {MARGIN} further (the lower end",
        "# for a metric where higher is better, the upper where lower is better), rounded",
        "# outward: the run it came from passes, a clear regression fails. Comments give the",
        "# value [95% CI] n. Tighten bounds as more episodes are recorded; the schema and every",
        "# metric: docs/user-guide/ci.md. Check it with `emrd gate RUN_DIR...`.",
    ]
    model = None
    for (name, condition), variants in sorted(cells.items()):
        if name != model:
            model = name
            lines.append(f"{name}:")
        lines.append(f"  {condition}:")
        for metric in names:
            lines += _bound(metrics[metric], variants.values())
    return "\n".join(lines) + "\n"


def _bound(metric: GateMetric, groups: Iterable[list[Any]]) -> list[str]:
    """``    aec: {min: 0.78}  # value ...`` for the loosest prompt variant, or nothing."""
    higher = metric.better == "higher"
    found = []
    for group in groups:
        e = metric.compute(sorted(group, key=lambda m: m.spec.case_id), rng_seed=0)
        if e.value is None or not math.isfinite(e.value):
            continue
        end = e.ci_low if higher else e.ci_high
        edge = (e.value if end is None else end) + (-MARGIN if higher else MARGIN)
        found.append((edge, e))
    if not found:
        return []
    edge, e = (min if higher else max)(found, key=lambda f: f[0])
    bound = min(1.0, max(0.0, (math.floor if higher else math.ceil)(edge * 100) / 100))
    ci = f"[{format_number(e.ci_low)}, {format_number(e.ci_high)}]"
    kind = "min" if higher else "max"
    return [f"    {metric.name}: {{{kind}: {bound:g}}}  # {format_number(e.value)} {ci} n={e.n}"]
