"""Remember rows: do the R^2 findings survive the choice of evaluation points?

The paper compares the Ebbinghaus curve with the Kaplan-Meier curve by R^2 without saying
at which times. Our default compares them on the KM curve's timeline (every distinct spell
duration; :func:`pytest_emrd.metrics.ebbinghaus_fit`, ``points="durations"``); these rows
recompute the
two R^2 findings of the validation table (planted exponential decay fits, R^2 >= 0.8; a hard
window fits worse than the decay of matched mean, gap >= 0.1) on the other two grids, and
list ``scout-serial``'s pooled R^2 on each. A finding that holds on every grid gets ``pass``
on each row; one that does not survive an alternative grid is a ``finding`` on that row.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence

from pytest_emrd.metrics import R2_POINTS, ebbinghaus
from pytest_emrd.validate._check import Check, Episode, fmt
from pytest_emrd.validate._remember import nearest_decay

#: Planted exponential decay must fit at least this well (as in the decay rows).
MIN_R2 = 0.8
#: A hard window must fit worse than the decay of matched mean by at least this much.
R2_GAP = 0.1


def r2_points_checks(
    decays: Mapping[float, Sequence[Episode]],
    windows: Mapping[int, Sequence[Episode]],
    serial: Sequence[Episode],
) -> list[Check]:
    """One row per grid of :data:`~pytest_emrd.metrics.R2_POINTS` (the default first)."""
    rows = []
    for points in R2_POINTS:
        decay = {m: ebbinghaus(t, points=points).pooled for m, t in decays.items()}
        window = {k: ebbinghaus(t, points=points).pooled for k, t in windows.items()}
        r2_serial = ebbinghaus(serial, points=points).pooled.r2
        exponential = all(f.r2 is not None and f.r2 >= MIN_R2 for f in decay.values())
        gaps = []
        finite = {m: f for m, f in decay.items() if f.efc and math.isfinite(f.efc)}
        for fit in window.values():
            if fit.efc is None or not math.isfinite(fit.efc) or not finite or fit.r2 is None:
                gaps.append(-math.inf)
                continue
            gaps.append((finite[nearest_decay(fit.efc, finite)].r2 or 0.0) - fit.r2)
        survives = exponential and all(g >= R2_GAP for g in gaps)
        default = points == R2_POINTS[0]
        verdict = "pass" if survives else ("fail" if default else "finding")
        recovered = (
            "decay " + " / ".join(fmt(f.r2, 2) for f in decay.values())
            + "; window " + " / ".join(fmt(f.r2, 2) for f in window.values())
            + f"; serial {fmt(r2_serial, 2)}"
        )  # fmt: skip
        rows.append(
            Check("Remember", f"R^2 findings on evaluation points '{points}'"
                  + (" (default)" if default else ""),
                  f"decay R^2 >= {MIN_R2}; window gap >= {R2_GAP}", recovered,
                  "both findings hold", verdict,
                  f"decay {', '.join(f'{m:g}' for m in decay)}; window "
                  f"{', '.join(str(k) for k in window)}; smallest gap "
                  f"{fmt(min(gaps, default=math.nan), 2)}",
                  {"points": points, "min_gap": min(gaps, default=math.nan),
                   "serial_r2": r2_serial,
                   **{f"r2_decay_{m:g}": f.r2 for m, f in decay.items()},
                   **{f"r2_window_{k}": f.r2 for k, f in window.items()}})
        )  # fmt: skip
    return rows
