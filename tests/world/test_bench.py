"""``emrd bench world`` reports the three world figures with their targets."""

from __future__ import annotations

from pytest_emrd.bench import world


def test_world_bench_reports_step_episode_and_layout_figures() -> None:
    figures = {f.figure: f for f in world.run(repeat=1)}
    assert set(figures) == {"world.step_ms", "world.episode_s", "world.layout_ms"}
    assert [(f.unit, f.target, f.n) for f in figures.values()] == [
        ("ms", 15.0, 1),
        ("s", 1.0, 1),
        ("ms", 20.0, 1),
    ]
    assert all(f.value > 0 for f in figures.values())
