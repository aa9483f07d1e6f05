"""Measure what the pose line is worth: the mimic's PA and TBS with and without it.

Usage, from the repository root (about ten minutes on two cores; the reference agents answer
locally, nothing leaves the machine)::

    PYTHONPATH=$PWD python -m pytest benchmarks -q -p no:cacheprovider -n 2 \\
        --emrd-model=mimic --emrd-model=mimic-reckon --emrd-condition=baseline \\
        --emrd-record-mode=all --emrd-cassettes=/tmp/pose-cassettes --emrd-results=RUN
    PYTHONPATH=$PWD python docs/interpretation/measure_pose_line.py RUN

``mimic`` places what it sees from the engine's ``Pose:`` line, ``mimic-reckon`` from its own
dead reckoning (:mod:`pytest_emrd.reference._odometry`); both walk the same path, so the
difference is the line's. Paired bootstrap intervals: ``emrd report RUN --compare-models mimic
mimic-reckon``.
"""

from __future__ import annotations

import statistics
import sys
from pathlib import Path

from pytest_emrd.metrics import tbs_curve
from pytest_emrd.run import load_run_episodes, measure_episodes


def main(run_dir: Path) -> None:
    measured = measure_episodes(load_run_episodes([run_dir]))
    print("model          episodes  AEC     PA      TBS(25)  TBS(50)")
    for model in ("mimic", "mimic-reckon"):
        mine = [m for m in measured if m.spec.model == model]
        curve = tbs_curve(mine)
        aec = statistics.fmean(m.aec for m in mine if m.aec is not None)
        pa = statistics.fmean(m.pa for m in mine if m.pa is not None)
        tbs = f"{curve.mean[24]:.3f}    {curve.mean[49]:.3f}"
        print(f"{model:<14} {len(mine):<9} {aec:.3f}   {pa:.3f}   {tbs}")


if __name__ == "__main__":
    main(Path(sys.argv[1]))
