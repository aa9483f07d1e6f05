"""The EMRD benchmark suite (``pytest --pyargs pytest_emrd.benchmarks``, or ``pytest
benchmarks`` in a checkout of pytest-emrd).

``test_episode[<model>-<condition>-<spawn>-epNN]`` runs (or replays, or reuses from the run
directory) one episode and fails only when the episode errored: transport exhausted,
cassette missing or divergent. ``test_gate[<model>-<condition>-<metric>]`` aggregates the
episodes of one model x condition and checks them against ``thresholds.yaml``. Select with
``--emrd-model``, ``--emrd-condition``, ``--emrd-spawn``, ``--emrd-episodes`` or ``-k``.
"""

from __future__ import annotations

import pytest

from pytest_emrd.gate import Verdict
from pytest_emrd.run import StoredEpisode


def test_episode(emrd_episode: StoredEpisode) -> None:
    head = emrd_episode.head  # a finished episode's trajectory is not decoded to check this
    if head.status == "errored":
        pytest.fail(f"{head.spec.case_id} errored: {head.error}", pytrace=False)


def test_gate(emrd_verdict: Verdict) -> None:
    if not emrd_verdict.passed:
        pytest.fail(emrd_verdict.explain(), pytrace=False)
