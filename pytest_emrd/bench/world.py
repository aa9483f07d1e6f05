"""``emrd bench world``: layout generation, one simulator step, one 50-step episode.

The step and episode figures drive the built-in simulator with a fixed explorer that turns
and walks up to what it sees (every step moves or turns, so every step renders and encodes
a new frame); a failed or repeated pose would hit the frame cache and flatter the figure.
"""

from __future__ import annotations

from pytest_emrd.bench import Figure, median_seconds
from pytest_emrd.trajectory import MAX_STEPS
from pytest_emrd.world import Observation, generate_layout, ground_truth, make_simulator

LAYOUTS_PER_REPEAT = 10
STEPS_PER_REPEAT = 20
SEED = 20240611


def _explore(obs: Observation, i: int) -> str:
    """Deterministic explorer: two right turns, then walk to the next object in view."""
    if i % 3 == 2 and obs.visible:
        return f"Goto({obs.visible[(i // 3) % len(obs.visible)].object_id})"
    return "Turn(Right)"


def _episode(seed: int, steps: int) -> None:
    layout = generate_layout(seed)
    sim = make_simulator("builtin")
    obs = sim.reset(layout, "baseline", "office", seed)
    ground_truth(layout, sim.spawn_pose, "Office")
    for i in range(steps):
        obs = sim.step(_explore(obs, i))
        if obs.done:
            break
    sim.close()


def run(*, repeat: int) -> list[Figure]:
    seeds = iter(range(SEED, SEED + 10_000))

    def layouts() -> None:
        for _ in range(LAYOUTS_PER_REPEAT):
            generate_layout(next(seeds))

    layout_s = median_seconds(layouts, repeat=repeat) / LAYOUTS_PER_REPEAT
    layout = generate_layout(SEED)
    sim = make_simulator("builtin")
    state = {"obs": sim.reset(layout, "baseline", "office", SEED), "i": 0}

    def steps() -> None:
        for _ in range(STEPS_PER_REPEAT):
            state["obs"] = sim.step(_explore(state["obs"], state["i"]))  # type: ignore[arg-type]
            state["i"] += 1  # type: ignore[operator]

    step_s = median_seconds(steps, repeat=repeat) / STEPS_PER_REPEAT
    episode_s = median_seconds(lambda: _episode(next(seeds), MAX_STEPS), repeat=repeat)
    return [
        Figure("world.step_ms", step_s * 1e3, "ms", 15.0, repeat),
        Figure("world.episode_s", episode_s, "s", 1.0, repeat),
        Figure("world.layout_ms", layout_s * 1e3, "ms", 20.0, repeat),
    ]
