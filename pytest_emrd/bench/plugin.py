"""``emrd bench plugin``: the plugin's own cost in a pytest session.

* ``plugin.collect_7x240_s`` — collection of the benchmark suite for the seven paper models
  x 240 cases (3 conditions x 4 spawns x 20 episodes, plus their gate items), as pytest
  reports it ("collected in X s": the collection phase, excluding interpreter start-up and
  plugin import). Target 2 s.
"""

from __future__ import annotations

import re
import statistics
import subprocess
import sys
from pathlib import Path

from pytest_emrd.bench import Figure

ROOT = Path(__file__).resolve().parents[2]
PAPER_MODELS = (
    "gemini",
    "gpt",
    "claude",
    "qwen3-vl-32b",
    "ovis2-34b",
    "pixtral-12b",
    "internvl3-14b",
)
_COLLECTED = re.compile(r"(\d+) tests? collected in ([0-9.]+)s")


def _collect_once() -> tuple[int, float]:
    cmd = [sys.executable, "-m", "pytest", "benchmarks", "--collect-only", "-q"]
    cmd += ["-p", "no:cacheprovider", *(f"--emrd-model={m}" for m in PAPER_MODELS)]
    done = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True, check=False)
    match = _COLLECTED.search(done.stdout)
    if done.returncode != 0 or match is None:
        raise RuntimeError(f"collection failed:\n{done.stdout[-3000:]}{done.stderr[-2000:]}")
    return int(match[1]), float(match[2])


def run(*, repeat: int) -> list[Figure]:
    _collect_once()
    samples = [_collect_once() for _ in range(repeat)]
    count = samples[0][0]
    if count < len(PAPER_MODELS) * 240:
        raise RuntimeError(f"collected {count} items, expected >= {len(PAPER_MODELS) * 240}")
    return [
        Figure("plugin.collect_7x240_s", statistics.median(s for _, s in samples), "s", 2.0, repeat)
    ]
