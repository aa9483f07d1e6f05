"""``emrd render --seed S --condition C --spawn ROOM --out DIR``: look at the built-in world.

Writes the spawn view and a sweep (the JPEG frames the model would be shown after
``Turn(Right)`` three times), and ``map.png``, a top-down plan with the agent.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from pytest_emrd.rooms import ROOM_SLUGS, SLUG_ROOMS
from pytest_emrd.trajectory import CONDITIONS

VIEWS = ("spawn", "right", "behind", "left")


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("render", help="write frames and a top-down map of the built-in world")
    p.add_argument("--seed", type=int, required=True, help="world seed (layout and spawn pose)")
    p.add_argument("--condition", choices=CONDITIONS, default="baseline", help="default baseline")
    p.add_argument("--spawn", choices=list(SLUG_ROOMS), default="office", help="spawn room slug")
    p.add_argument("--out", type=Path, required=True, help="directory to write into")
    p.set_defaults(func=_run)


def _run(args: argparse.Namespace) -> int:
    from pytest_emrd.world import condition_params, generate_layout, make_simulator
    from pytest_emrd.world._topdown import plan_png

    layout = generate_layout(args.seed)
    sim = make_simulator("builtin")
    obs = sim.reset(layout, args.condition, args.spawn, args.seed)
    args.out.mkdir(parents=True, exist_ok=True)
    room = SLUG_ROOMS[args.spawn]
    print(f"seed {args.seed}, {args.condition}, spawn in {room} ({ROOM_SLUGS[room]})")
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
