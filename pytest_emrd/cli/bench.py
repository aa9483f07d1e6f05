"""``emrd bench [STAGE ...] [--json] [--repeat N]``."""

from __future__ import annotations

import argparse
import json

from pytest_emrd.bench import STAGES, format_table, run_stages


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("bench", help="measure the product's own speed and size on this machine")
    p.add_argument(
        "stages",
        nargs="*",
        default=["all"],
        metavar="STAGE",
        help=f"one or more of {', '.join(STAGES)}, or all (default)",
    )
    p.add_argument("--json", action="store_true", help="print one JSON list of figures")
    p.add_argument("--repeat", type=int, default=5, help="repetitions per timing (default 5)")
    p.set_defaults(func=_run)


def _run(args: argparse.Namespace) -> int:
    figures = run_stages(args.stages, repeat=args.repeat)
    if args.json:
        print(json.dumps([f.to_dict() for f in figures]))
    else:
        print(format_table(figures))
    return 0
