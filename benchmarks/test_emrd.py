"""This repository's entry point to the EMRD benchmark suite (``pytest benchmarks``).

The suite ships in the package, :mod:`pytest_emrd.benchmarks.test_emrd`; a model team runs
the same tests from its own repository with ``pytest --pyargs pytest_emrd.benchmarks``.
"""

from pytest_emrd.benchmarks.test_emrd import test_episode, test_gate

__all__ = ["test_episode", "test_gate"]
