"""Planted memory policies: perfect, exponential decay, capacity window, serial U-shape."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from pytest_emrd.agent.reference._memory import apply_memory, merge_view, uniform
from pytest_emrd.errors import ConfigError


def _memory(labels: list[str]) -> dict[str, dict]:
    return {label: {"type": "T", "x": 0.0, "z": 0.0} for label in labels}


def test_merge_view_refreshes_seen_objects_to_the_end() -> None:
    merged = merge_view(_memory(["a", "b", "c"]), [("a", {"x": 1}), ("d", {"x": 2})])
    assert list(merged) == ["b", "c", "a", "d"]
    assert merged["a"] == {"x": 1}


def test_perfect_keeps_everything() -> None:
    memory = _memory(list("abcdef"))
    kept = apply_memory(
        memory,
        in_view=frozenset(),
        planted={"memory": "perfect"},
        discovery=list(memory),
        draw=lambda _: 0.0,
    )
    assert kept == memory


@given(st.integers(1, 12), st.lists(st.text(min_size=1, max_size=3), unique=True, max_size=30))
def test_window_keeps_the_k_most_recent(k: int, labels: list[str]) -> None:
    kept = apply_memory(
        _memory(labels),
        in_view=frozenset(),
        planted={"memory": "window", "k": k},
        discovery=labels,
        draw=lambda _: 0.0,
    )
    assert list(kept) == labels[-k:] if labels else kept == {}


def test_decay_never_drops_objects_in_view() -> None:
    memory = _memory(list("abc"))
    kept = apply_memory(
        memory,
        in_view=frozenset("abc"),
        planted={"memory": "decay", "mean_steps": 0.01},
        discovery=list("abc"),
        draw=lambda _: 0.0,
    )
    assert kept == memory


@pytest.mark.parametrize("mean_steps", [2.0, 8.0])
def test_decay_survival_is_exponential_with_the_planted_mean(mean_steps: float) -> None:
    """Simulate many out-of-view objects: survival after t steps is exp(-t / m)."""
    labels = [f"obj{i}" for i in range(4000)]
    alive, survival = set(labels), []
    for step in range(12):
        memory = {label: {} for label in labels if label in alive}
        seed = f"step{step}".encode()
        kept = apply_memory(
            memory,
            in_view=frozenset(),
            planted={"memory": "decay", "mean_steps": mean_steps},
            discovery=labels,
            draw=lambda label, seed=seed: uniform(seed, label),
        )
        alive = set(kept)
        survival.append(len(alive) / len(labels))
    expected = [math.exp(-(t + 1) / mean_steps) for t in range(12)]
    assert np.allclose(survival, expected, atol=0.025)


def test_serial_protects_first_and_last_thirds() -> None:
    labels = [f"o{i}" for i in range(9)]
    kept = apply_memory(
        _memory(labels),
        in_view=frozenset(),
        planted={"memory": "serial", "mean_steps": 1e-9},
        discovery=labels,
        draw=lambda _: 0.5,
    )
    assert list(kept) == ["o0", "o1", "o2", "o6", "o7", "o8"]


def test_uniform_is_deterministic_and_spread() -> None:
    assert uniform(b"s", "a") == uniform(b"s", "a") != uniform(b"t", "a")
    draws = [uniform(b"seed", str(i)) for i in range(2000)]
    assert min(draws) >= 0.0 and max(draws) < 1.0
    assert abs(float(np.mean(draws)) - 0.5) < 0.03


def test_unknown_memory_kind() -> None:
    with pytest.raises(ConfigError, match="planted memory='sieve'"):
        apply_memory(
            {}, in_view=frozenset(), planted={"memory": "sieve"}, discovery=[], draw=lambda _: 0.0
        )
