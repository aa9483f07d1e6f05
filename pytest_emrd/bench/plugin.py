"""``emrd bench plugin``: the plugin's own cost in a pytest session.

* ``plugin.collect_7x240_s`` — the whole process of ``pytest benchmarks --collect-only -q``
  for the seven paper models x 240 cases (3 conditions x 4 spawns x 20 episodes, plus their
  gate items): interpreter start-up, pytest and every installed plugin, collection and the
  end of the session, wall time. Target 1.5 s. ``plugin.collect_7x240_cpu_s``: that
  process's CPU time (user + system), which other load on the machine stretches less.
* ``plugin.empty_session_s`` — the floor under it: the same command on one empty test file
  with pytest-emrd switched off (``-p no:emrd``), i.e. the interpreter, pytest and the other
  installed plugins (hypothesis, anyio, xdist) alone; ``plugin.empty_session_cpu_s`` its CPU
  time. With ``PYTHONDONTWRITEBYTECODE=1`` pytest re-rewrites every plugin package's modules
  on every run (no cached pyc), so this floor is higher there than on a default install.
"""

from __future__ import annotations

import re
import statistics
import sys
import tempfile
from pathlib import Path

from pytest_emrd.bench import Figure, run_timed

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
_PYTEST = (sys.executable, "-m", "pytest", "--collect-only", "-q", "-p", "no:cacheprovider")


def _collect_once() -> tuple[int, float, float]:
    cmd = [*_PYTEST, "benchmarks", *(f"--emrd-model={m}" for m in PAPER_MODELS)]
    done, wall, cpu = run_timed(cmd, cwd=ROOT)
    match = _COLLECTED.search(done.stdout)
    if done.returncode != 0 or match is None:
        raise RuntimeError(f"collection failed:\n{done.stdout[-3000:]}{done.stderr[-2000:]}")
    return int(match[1]), wall, cpu


def _empty_once(folder: Path) -> tuple[float, float]:
    done, wall, cpu = run_timed([*_PYTEST, "-p", "no:emrd", "test_empty.py"], cwd=folder)
    if done.returncode != 0:
        raise RuntimeError(f"empty session failed:\n{done.stdout[-3000:]}{done.stderr[-2000:]}")
    return wall, cpu


def run(*, repeat: int) -> list[Figure]:
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        (folder / "test_empty.py").write_text("def test_nothing():\n    pass\n")
        _collect_once()
        _empty_once(folder)
        samples, floor = [], []
        for _ in range(repeat):  # alternated, so both see the same load
            samples.append(_collect_once())
            floor.append(_empty_once(folder))
    count = samples[0][0]
    if count < len(PAPER_MODELS) * 240:
        raise RuntimeError(f"collected {count} items, expected >= {len(PAPER_MODELS) * 240}")
    median = statistics.median
    return [
        Figure("plugin.collect_7x240_s", median(s[1] for s in samples), "s", 1.5, repeat),
        Figure("plugin.collect_7x240_cpu_s", median(s[2] for s in samples), "s", None, repeat),
        Figure("plugin.empty_session_s", median(w for w, _ in floor), "s", None, repeat),
        Figure("plugin.empty_session_cpu_s", median(c for _, c in floor), "s", None, repeat),
    ]
