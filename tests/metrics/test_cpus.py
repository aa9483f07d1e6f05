"""The metrics agree to 1e-9 whichever BLAS kernel OpenBLAS picks for the CPU.

Each core type runs in a fresh process (OpenBLAS reads ``OPENBLAS_CORETYPE`` once, at load).
A kernel whose instructions the CPU lacks dies with SIGILL, so only the kernels this CPU can
execute are forced; the others are skipped with the flags they need.
"""

from __future__ import annotations

import json
import os
import platform
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

#: The CPU flags each forced OpenBLAS kernel executes (OpenBLAS ``driver/others/dynamic.c``).
#: ``Prescott`` (SSE3) runs on every x86-64 CPU and is the reference the others must agree with.
KERNEL_FLAGS = {
    "Haswell": {"avx2", "fma"},
    "Zen": {"avx2", "fma"},
    "SkylakeX": {"avx512f", "avx512cd", "avx512bw", "avx512dq", "avx512vl"},
}


def _cpu_flags() -> set[str] | None:
    """The CPU's instruction-set flags from ``/proc/cpuinfo``, or None where it cannot be read."""
    try:
        text = Path("/proc/cpuinfo").read_text()
    except OSError:
        return None
    for line in text.splitlines():
        if line.startswith("flags"):
            return set(line.partition(":")[2].split())
    return None


def _values(coretype: str) -> list[float | None]:
    env = {**os.environ, "OPENBLAS_CORETYPE": coretype}
    root = Path(__file__).resolve().parents[2]
    env["PYTHONPATH"] = os.pathsep.join(filter(None, [str(root), env.get("PYTHONPATH")]))
    done = subprocess.run(
        [sys.executable, "-c", SCRIPT], env=env, capture_output=True, text=True, check=True
    )
    return json.loads(done.stdout)


@pytest.mark.slow
@pytest.mark.parametrize("coretype", sorted(KERNEL_FLAGS))
def test_each_kernel_the_cpu_runs_gives_the_reference_metrics_to_1e_9(coretype: str) -> None:
    if platform.machine().lower() not in {"x86_64", "amd64"}:
        pytest.skip(f"OpenBLAS core types are x86-64 kernels; this CPU is {platform.machine()}")
    flags = _cpu_flags()
    if flags is None:
        pytest.skip("/proc/cpuinfo is unreadable, so the kernels this CPU can run are unknown")
    missing = KERNEL_FLAGS[coretype] - flags
    if missing:
        pytest.skip(f"{coretype} needs {', '.join(sorted(missing))}, which this CPU lacks")
    reference, forced = _values("Prescott"), _values(coretype)
    assert len(reference) == len(forced) > 100
    for a, b in zip(reference, forced, strict=True):
        assert (a is None) == (b is None)
        if a is not None and b is not None:
            assert a == pytest.approx(b, rel=1e-9, abs=1e-9)


def test_the_cpu_flag_reader_finds_the_baseline_instruction_sets() -> None:
    flags = _cpu_flags()
    if flags is None or platform.machine().lower() not in {"x86_64", "amd64"}:
        pytest.skip("no x86-64 /proc/cpuinfo to read")
    assert {"sse2", "sse3"} <= flags or "pni" in flags
