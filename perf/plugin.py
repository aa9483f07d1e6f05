"""``python -m perf plugin``: the plugin's own cost in a pytest session.

* ``plugin.collect_7x240_s`` — the whole process of ``pytest benchmarks --collect-only -q``
  for the seven paper models x 240 cases (3 conditions x 4 spawns x 20 episodes, plus their
  gate items): interpreter start-up, pytest and every installed plugin, collection and the
  end of the session, wall time, under Python's default bytecode policy (``.pyc`` cached, as
  on a user's machine from the second run on; :func:`~perf.python_env`, warmed
  up before timing). Target 1.5 s. ``plugin.collect_7x240_cpu_s``: that process's CPU
  time (user + system), which other load on the machine stretches less.
* ``plugin.empty_session_s`` — the floor under it: the same command on one empty test file
  with pytest-emrd switched off (``-p no:emrd``), i.e. the interpreter, pytest and the other
  installed plugins (hypothesis, anyio, xdist) alone; ``plugin.empty_session_cpu_s`` its CPU
  time.
* ``plugin.collect_7x240_nobytecode_s`` and ``plugin.empty_session_nobytecode_s`` — the same
  two commands with ``PYTHONDONTWRITEBYTECODE=1`` (how this development machine runs), no
  target: pytest marks for assertion rewriting every package of every distribution with a
  ``pytest11`` entry point (hypothesis, anyio, xdist, ours) and, unable to cache what it
  rewrote, parses and compiles them again in every process, as Python does for every module
  of an editable install.
"""

from __future__ import annotations

import re
import statistics
import sys
import tempfile
from pathlib import Path

from perf import ROOT, Figure, python_env, run_timed

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


def _session(cmd: list[str], cwd: Path, env: dict[str, str]) -> tuple[int, float, float]:
    """Items collected, wall and CPU seconds of one ``pytest --collect-only`` process."""
    done, wall, cpu = run_timed([*_PYTEST, *cmd], cwd=cwd, env=env)
    match = _COLLECTED.search(done.stdout)
    if done.returncode != 0 or match is None:
        raise RuntimeError(f"collection failed:\n{done.stdout[-3000:]}{done.stderr[-2000:]}")
    return int(match[1]), wall, cpu


def run(*, repeat: int, warmup: int) -> list[Figure]:
    policies = {"": python_env(bytecode=True), "_nobytecode": python_env(bytecode=False)}
    samples: dict[str, list[tuple[int, float, float]]] = {}
    with tempfile.TemporaryDirectory() as tmp:
        (Path(tmp) / "test_empty.py").write_text("def test_nothing():\n    pass\n")
        sessions = {
            "collect_7x240": (["benchmarks", *(f"--emrd-model={m}" for m in PAPER_MODELS)], ROOT),
            "empty_session": (["-p", "no:emrd", "test_empty.py"], Path(tmp)),
        }
        for _ in range(warmup):  # filling the bytecode cache
            for cmd, cwd in sessions.values():
                _session(cmd, cwd, policies[""])
        for _ in range(repeat):  # alternated, so every command sees the same load
            for name, (cmd, cwd) in sessions.items():
                for policy, env in policies.items():
                    samples.setdefault(name + policy, []).append(_session(cmd, cwd, env))
    count = samples["collect_7x240"][0][0]
    if count < len(PAPER_MODELS) * 240:
        raise RuntimeError(f"collected {count} items, expected >= {len(PAPER_MODELS) * 240}")
    figures = []
    for name, runs in samples.items():
        target = 1.5 if name == "collect_7x240" else None
        wall, cpu = (statistics.median(run[i] for run in runs) for i in (1, 2))
        figures.append(Figure(f"plugin.{name}_s", wall, "s", target, repeat))
        if "nobytecode" not in name:
            figures.append(Figure(f"plugin.{name}_cpu_s", cpu, "s", None, repeat))
    return figures
