"""``python -m perf world`` reports the four world figures with their targets."""

from __future__ import annotations

from perf import world


def test_world_bench_reports_step_render_episode_and_layout_figures() -> None:
    figures = {f.figure: f for f in world.run(repeat=1, warmup=1)}
    assert list(figures) == [
        "world.step_ms",
        "world.render_ms",
        "world.episode_s",
        "world.layout_ms",
    ]
    assert [(f.unit, f.target, f.n) for f in figures.values()] == [
        ("ms", 15.0, 1),
        ("ms", None, 1),
        ("s", 1.0, 1),
        ("ms", 20.0, 1),
    ]
    assert all(f.value > 0 for f in figures.values())


def test_render_figure_covers_every_condition_on_the_paper_office() -> None:
    frames = world._frames()
    assert len(frames) == 3 * world.STEPS_PER_REPEAT
    assert {params.name for _, _, params, _ in frames} == {"baseline", "low_light", "texture"}
    assert len({(pose, params.name) for _, pose, params, _ in frames}) > 30
