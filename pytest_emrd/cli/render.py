"""``emrd render --spawn ROOM --episode N --condition C --out DIR``: look at the built-in world.

The world of the benchmark episode of that spawn room and index
(:func:`pytest_emrd.world.episode_world`). Writes the JPEG frames the model would be shown at
spawn and after ``Turn(Right)`` three times, and ``map.png``, a top-down plan with the agent.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from pytest_emrd.rooms import SLUG_ROOMS
from pytest_emrd.trajectory import CONDITIONS, LAYOUTS, EpisodeSpec

VIEWS = ("spawn", "right", "behind", "left")


HELP = "write frames and a top-down map of the built-in world"


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--spawn", choices=list(SLUG_ROOMS), default="office", help="spawn room slug")
    p.add_argument("--episode", type=int, default=0, help="episode index (spawn pose), default 0")
    p.add_argument("--condition", choices=CONDITIONS, default="baseline", help="default baseline")
    p.add_argument(
        "--layouts",
        choices=LAYOUTS,
        default="paper",
        help="paper (the fixed office, default) or generated (the episode's own office)",
    )
    p.add_argument("--out", type=Path, required=True, help="directory to write into")


def run(args: argparse.Namespace) -> int:
    from pytest_emrd.world import condition_params, episode_world, make_simulator, plan_png

    spec = EpisodeSpec(
        model="-",
        condition=args.condition,
        spawn=args.spawn,
        episode=args.episode,
        layouts=args.layouts,
    )
    world = episode_world(spec)
    layout = world.layout
    sim = make_simulator("builtin")
    obs = sim.reset(layout, args.condition, world.spawn_room, world.seed)
    args.out.mkdir(parents=True, exist_ok=True)
    print(
        f"{args.layouts} layouts, {args.spawn} ep{args.episode:02d} (seed {world.seed}), "
        f"{args.condition}, spawn in {world.spawn_room}"
    )
    for i, view in enumerate(VIEWS):
        if i:
            obs = sim.step("Turn(Right)")
        path = args.out / f"{i:02d}_{view}.jpg"
        path.write_bytes(obs.jpeg)
        seen = ", ".join(v.object_id for v in obs.visible) or "nothing"
        print(f"{path}: {obs.feedback} Visible: {seen}")
    vis = condition_params(args.condition).visibility_distance
    plan = args.out / "map.png"
    plan.write_bytes(plan_png(layout, sim.spawn_pose, visibility=vis))
    print(f"{plan}: top-down plan")
    sim.close()
    return 0
