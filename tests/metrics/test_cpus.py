"""The metrics agree to 1e-9 whichever BLAS kernel OpenBLAS picks for the CPU.

Each core type runs in a fresh process (OpenBLAS reads ``OPENBLAS_CORETYPE`` once, at load).
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

#: Every episode metric of 12 synthetic episodes, as one flat list of numbers.
SCRIPT = """
import json, math
from pytest_emrd.metrics import as_episode_metrics
from pytest_emrd.metrics.synthetic import synthetic_grid

values = []
for m in as_episode_metrics(synthetic_grid(episodes=1)):
    values += [m.pa, m.aec, m.precision, m.hallucination_rate, m.sir, m.memory_strength]
    values += list(m.tbs) + [s.duration for s in m.spells] + [m.matched, m.unmatched]
print(json.dumps([None if v is None or not math.isfinite(v) else v for v in values]))
"""


def _values(coretype: str) -> list[float | None]:
    env = {**os.environ, "OPENBLAS_CORETYPE": coretype}
    root = Path(__file__).resolve().parents[2]
    env["PYTHONPATH"] = os.pathsep.join(filter(None, [str(root), env.get("PYTHONPATH")]))
    done = subprocess.run(
        [sys.executable, "-c", SCRIPT], env=env, capture_output=True, text=True, check=True
    )
    return json.loads(done.stdout)


@pytest.mark.slow
def test_haswell_and_skylakex_kernels_give_the_same_metrics_to_1e_9() -> None:
    haswell, skylakex = _values("Haswell"), _values("SkylakeX")
    assert len(haswell) == len(skylakex) > 100
    for a, b in zip(haswell, skylakex, strict=True):
        assert (a is None) == (b is None)
        if a is not None and b is not None:
            assert a == pytest.approx(b, rel=1e-9, abs=1e-9)
