"""``emrd validate [--episodes N] [--out DIR] [--jobs J] [--family F]``: do the metrics recover
the truth?

Runs the reference agents with planted cognition (the scout family and ``prior``; ``mimic``
groups that each move one map-writing knob) on the built-in world, checks that every metric
recovers what was planted and that the statistics reproduce the paper's tables, prints the
table and writes ``validation.md`` and ``validation.json`` under ``--out``, where episodes
are cached. Exit status: 0 when no check fails (``finding`` rows do not), 1 when one
fails, 2 on a usage error.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from pytest_emrd.errors import check_positive_int

HELP = "check that the metrics recover the reference agents' planted cognition"


def add_arguments(p: argparse.ArgumentParser) -> None:
    from pytest_emrd.validate import FAMILIES, FULL_EPISODES

    p.add_argument(
        "--episodes",
        type=int,
        default=FULL_EPISODES,
        metavar="N",
        help=f"episodes per spawn room and agent (default: {FULL_EPISODES}, as the paper)",
    )
    p.add_argument(
        "--out",
        type=Path,
        default=Path("emrd-validation"),
        metavar="DIR",
        help="episode cache and output folder (default: ./emrd-validation)",
    )
    p.add_argument("--jobs", type=int, default=2, metavar="J", help="worker processes (default: 2)")
    p.add_argument(
        "--family",
        action="append",
        choices=sorted(FAMILIES),
        help="agent family to validate, repeatable (default: all): scout (memory, exploration "
        "and decision metrics, with prior) or mimic (VLM-like map writing)",
    )


def run(args: argparse.Namespace) -> int:
    from pytest_emrd._files import write_bytes_atomic
    from pytest_emrd.protocol import protocol_version
    from pytest_emrd.validate import (
        FAMILIES,
        Plan,
        Progress,
        markdown,
        run_plan,
        to_json,
        validation_report,
    )

    check_positive_int("--episodes", args.episodes)
    check_positive_int("--jobs", args.jobs)
    families = args.family or sorted(FAMILIES)
    plan = Plan(args.episodes, tuple(g for f in families for g in FAMILIES[f]))

    def progress(p: Progress) -> None:
        if p.done % 20 == 0 or p.done == p.total:
            print(
                f"[{p.done}/{p.total}] {p.case_id} {p.status} ({p.seconds:.0f} s)",
                file=sys.stderr,
                flush=True,
            )

    groups = run_plan(plan, args.out, jobs=args.jobs, on_episode=progress)
    report = validation_report(groups, episodes=args.episodes, protocol=protocol_version("builtin"))
    text = markdown(report)
    print(text, end="")
    write_bytes_atomic(args.out / "validation.md", text.encode())
    write_bytes_atomic(args.out / "validation.json", to_json(report).encode())
    print(f"wrote {args.out / 'validation.md'} and {args.out / 'validation.json'}")
    return 1 if report.failed else 0
