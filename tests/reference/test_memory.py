"""Planted memory policies: perfect, none, geometric decay, capacity window, serial U-shape."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from pytest_emrd.errors import ConfigError
from pytest_emrd.reference._memory import (
    apply_memory,
    drop_probability,
    merge_view,
    uniform,
)


def _memory(labels: list[str]) -> dict[str, dict]:
    return {label: {"type": "T", "x": 0.0, "z": 0.0} for label in labels}


def test_merge_view_refreshes_seen_objects_to_the_end() -> None:
    merged = merge_view(_memory(["a", "b", "c"]), {"a": {"x": 1}, "d": {"x": 2}})
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
    """With m = 1 (p = 1) every out-of-view object goes at once; objects in view stay."""
    kept = apply_memory(
        _memory(list("abcd")),
        in_view=frozenset("abc"),
        planted={"memory": "decay", "mean_steps": 1.0},
        discovery=list("abcd"),
        draw=lambda _: 0.999,
    )
    assert list(kept) == ["a", "b", "c"]


@pytest.mark.parametrize("mean_steps", [2.0, 8.0])
def test_decay_retention_is_geometric_with_the_planted_mean(mean_steps: float) -> None:
    """Simulate many out-of-view objects: S(t) = (1 - 1/m)^t and the mean retention is m."""
    labels = [f"obj{i}" for i in range(4000)]
    alive, survival, dropped_at = set(labels), [], {}
    for step in range(1, 121):
        memory = {label: {} for label in labels if label in alive}
        seed = f"step{step}".encode()
        kept = apply_memory(
            memory,
            in_view=frozenset(),
            planted={"memory": "decay", "mean_steps": mean_steps},
            discovery=labels,
            draw=lambda label, seed=seed: uniform(seed, label),
        )
        dropped_at.update(dict.fromkeys(alive - set(kept), step))
        alive = set(kept)
        survival.append(len(alive) / len(labels))
    expected = [(1.0 - 1.0 / mean_steps) ** t for t in range(1, 13)]
    assert np.allclose(survival[:12], expected, atol=0.025)
    assert not alive
    assert float(np.mean(list(dropped_at.values()))) == pytest.approx(mean_steps, rel=0.04)


@pytest.mark.parametrize("mean_steps", [0.99, 0.0, -3.0], ids=["below-one", "zero", "negative"])
def test_decay_mean_below_one_step_is_refused(mean_steps: float) -> None:
    with pytest.raises(ConfigError, match=f"mean_steps={mean_steps!r} must be >= 1"):
        drop_probability(mean_steps)


def test_none_keeps_nothing() -> None:
    kept = apply_memory(
        _memory(list("abc")),
        in_view=frozenset("abc"),
        planted={"memory": "none"},
        discovery=list("abc"),
        draw=lambda _: 0.5,
    )
    assert kept == {}


def _serial(labels: list[str], expected: int | None) -> list[str]:
    kept = apply_memory(
        _memory(labels),
        in_view=frozenset(),
        planted={"memory": "serial", "mean_steps": 1.0},
        discovery=labels,
        draw=lambda _: 0.5,
        expected=expected,
    )
    return list(kept)


def test_serial_protects_thirds_of_the_expected_total() -> None:
    """15 objects announced, 9 found so far: ranks 0-4 early, 5-9 middle (out of view: go)."""
    labels = [f"o{i}" for i in range(9)]
    assert _serial(labels, 15) == ["o0", "o1", "o2", "o3", "o4"]
    late = [f"o{i}" for i in range(12)]
    assert _serial(late, 15) == ["o0", "o1", "o2", "o3", "o4", "o10", "o11"]


@pytest.mark.parametrize("expected", [None, 0], ids=["none", "zero"])
def test_serial_without_an_inventory_uses_the_objects_found_so_far(expected) -> None:
    labels = [f"o{i}" for i in range(9)]
    assert _serial(labels, expected) == ["o0", "o1", "o2", "o6", "o7", "o8"]


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
