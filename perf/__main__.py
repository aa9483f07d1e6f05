"""``python -m perf [STAGE ...] [--json] [--repeat N] [--mode both|warm|cold] [--warmup N]``.

Run from the root of a checkout (``pip install -e .`` done). Prints a table, or with
``--json`` one JSON list of figures, each ``{"figure", "value", "unit", "target", "n",
"higher_is_better"}``: the warm figures, then the cold ones (``<figure>_cold``).
``python perf/table.py FILE`` turns that JSON into the docs' performance table.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
from pathlib import Path

from perf import COLD_ENV, ROOT, STAGES, cold_figures, format_table, run_stages
from pytest_emrd.errors import EmrdError


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="python -m perf",
        description="Measure pytest-emrd's own speed and size on this machine, warm and cold.",
    )
    parser.add_argument(
        "stages",
        nargs="*",
        default=["all"],
        metavar="STAGE",
        help=f"one or more of {', '.join(STAGES)}, or all (default)",
    )
    parser.add_argument("--json", action="store_true", help="print one JSON list of figures")
    parser.add_argument(
        "--repeat",
        type=int,
        default=3,
        help="warm: timed repetitions per figure; cold: fresh processes per stage (default 3)",
    )
    parser.add_argument(
        "--mode",
        choices=("both", "warm", "cold"),
        default="both",
        help="warm figures, cold figures (fresh copy, fresh process), or both (default)",
    )
    parser.add_argument(
        "--warmup",
        type=int,
        default=1,
        help="untimed runs before the warm timings (default 1; a cold stage runs with 0)",
    )
    return parser


def _check_cold_copy() -> None:
    """A cold stage must measure the fresh copy, not an installed checkout elsewhere."""
    import pytest_emrd

    if os.environ.get(COLD_ENV) and ROOT not in Path(pytest_emrd.__file__).resolve().parents:
        raise EmrdError(
            f"cold run imported pytest_emrd from {pytest_emrd.__file__}, not from the fresh "
            f"copy {ROOT}; run python -m perf from the root of the checkout."
        )


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    try:
        _check_cold_copy()
        figures = []
        if args.mode in ("both", "warm"):
            figures += run_stages(args.stages, repeat=args.repeat, warmup=args.warmup)
        if args.mode in ("both", "cold"):
            figures += cold_figures(args.stages, repeat=args.repeat)
    except EmrdError as exc:
        print(f"python -m perf: error: {exc}", file=sys.stderr)
        return 2
    if args.json:
        print(json.dumps([f.to_dict() for f in figures]))
    else:
        print(format_table(figures))
    return 0


if __name__ == "__main__":
    sys.exit(main())
