"""``emrd thor-smoke``: confirm the ai2thor backend on a machine with a GPU and a THOR build.

Runs one scout episode per condition (no model, no network) on AI2-THOR and on the builtin
world, writes both trajectories as JSON, and prints how their shapes compare (status, steps,
rooms visited, room chosen, the first step where the actions part). THOR renders with its
own assets, so the shapes may part after a few steps; what must hold is that every THOR
episode runs to the end without THOR refusing anything. Exit status: 0 when it does, 1 when
not, 2 on a configuration error (no build, no Vulkan: the message names the fix).

    emrd thor-smoke --out smoke/ --local-executable-path ~/thor-CloudRendering-<commit>/...
    python -m pytest_emrd.cli thor-smoke --out smoke/         # the same
"""

from __future__ import annotations

import argparse
import json
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from pytest_emrd.rooms import SLUG_ROOMS
from pytest_emrd.trajectory import CONDITIONS, LAYOUTS, EpisodeSpec, Trajectory

REFUSED = "AI2-THOR refused"
"""What the backend's feedback says when THOR refused a step."""


@dataclass(frozen=True)
class Comparison:
    """One condition's episode on both backends."""

    condition: str
    builtin: Trajectory
    thor: Trajectory

    @property
    def refused(self) -> tuple[int, ...]:
        """Indices of THOR steps whose action THOR refused."""
        return tuple(s.index for s in self.thor.steps if REFUSED in s.feedback)

    @property
    def ok(self) -> bool:
        """The THOR episode ran to its end and THOR refused nothing."""
        return self.thor.status != "errored" and not self.refused

    @property
    def parted_at(self) -> int | None:
        """First step index where the two agents acted differently (None: never)."""
        for a, b in zip(self.builtin.steps, self.thor.steps, strict=False):
            if (a.action, a.success, a.room) != (b.action, b.success, b.room):
                return a.index
        if len(self.builtin.steps) != len(self.thor.steps):
            return min(len(self.builtin.steps), len(self.thor.steps))
        return None

    def lines(self) -> list[str]:
        b, t = self.builtin, self.thor
        parted = self.parted_at
        return [
            f"{self.condition}: {'OK' if self.ok else 'FAILED'}",
            f"  status        builtin={b.status} ai2thor={t.status}"
            + (f" ({t.error})" if t.error else ""),
            f"  steps         builtin={len(b.steps)} ai2thor={len(t.steps)}",
            f"  rooms visited builtin={sorted(b.rooms_visited)} ai2thor={sorted(t.rooms_visited)}",
            f"  chosen room   builtin={b.chosen_room} ai2thor={t.chosen_room}",
            "  same actions throughout" if parted is None else f"  actions part at step {parted}",
            *(
                [f"  THOR refused steps {list(self.refused)}: {t.steps[self.refused[0]].feedback}"]
                if self.refused
                else []
            ),
        ]


def run_smoke(
    *, spawn: str, episode: int, layouts: str, out: Path, backend_options: Mapping[str, Any]
) -> list[Comparison]:
    """One scout episode per condition on both backends; trajectories go to ``out``."""
    from contextlib import closing

    from pytest_emrd.episode import SimulatorPool, run_episode

    out.mkdir(parents=True, exist_ok=True)
    results = []
    with closing(SimulatorPool(backend_options)) as pool:
        for condition in CONDITIONS:
            runs = {}
            for backend in ("builtin", "ai2thor"):
                spec = EpisodeSpec(
                    "scout",
                    condition,
                    spawn,
                    episode,
                    modality="both",
                    layouts=layouts,
                    backend=backend,
                )
                traj = pool.run(spec) if backend == "ai2thor" else run_episode(spec)
                path = out / f"{condition}-{backend}.json"
                path.write_text(json.dumps(traj.to_dict(), indent=1), encoding="utf-8")
                runs[backend] = traj
            results.append(Comparison(condition, runs["builtin"], runs["ai2thor"]))
    return results


def run(args: argparse.Namespace) -> int:
    """Run the smoke episodes of parsed ``args``; print the comparison; 0 when all is OK."""
    options: dict[str, Any] = {"start_timeout": args.start_timeout}
    if args.local_executable_path:
        options["local_executable_path"] = args.local_executable_path
    if args.gpu_device is not None:
        options["gpu_device"] = args.gpu_device
    if args.allow_download:
        options["allow_download"] = True
    results = run_smoke(
        spawn=args.spawn,
        episode=args.episode,
        layouts=args.layouts,
        out=args.out,
        backend_options=options,
    )
    for result in results:
        print("\n".join(result.lines()))
    print(f"trajectories: {args.out}")
    return 0 if all(r.ok for r in results) else 1


HELP = "confirm the ai2thor backend on a GPU machine"


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--out", type=Path, required=True, help="directory for the trajectories")
    p.add_argument("--spawn", choices=list(SLUG_ROOMS), default="office", help="default office")
    p.add_argument("--episode", type=int, default=0, help="episode index, default 0")
    p.add_argument("--layouts", choices=LAYOUTS, default="paper", help="default paper")
    p.add_argument(
        "--local-executable-path", help="a THOR build's executable (default: ai2thor's cache)"
    )
    p.add_argument("--gpu-device", type=int, help="CUDA device index for CloudRendering")
    p.add_argument("--start-timeout", type=float, default=300.0, help="seconds, default 300")
    p.add_argument(
        "--allow-download", action="store_true", help="let ai2thor download a missing build"
    )
