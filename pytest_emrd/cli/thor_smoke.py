"""``emrd thor-smoke --out DIR``: one episode per condition on AI2-THOR vs the builtin world
(:mod:`pytest_emrd.cli._smoke`; needs the ``thor`` extra, a GPU and a THOR build)."""

from __future__ import annotations

import argparse
from pathlib import Path

from pytest_emrd.rooms import SLUG_ROOMS
from pytest_emrd.trajectory import LAYOUTS


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("thor-smoke", help="confirm the ai2thor backend on a GPU machine")
    add_arguments(p)
    p.set_defaults(func=_run)


def add_arguments(p: argparse.ArgumentParser) -> None:
    """The command's options (``emrd thor-smoke`` and ``python -m ...thor.smoke``)."""
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


def _run(args: argparse.Namespace) -> int:
    from pytest_emrd.cli._smoke import run

    return run(args)
