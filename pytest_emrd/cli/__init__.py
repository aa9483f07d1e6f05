"""The ``emrd`` console script.

Each subcommand lives in its own module under ``pytest_emrd.cli`` and exposes
``register(subparsers)``; heavy imports happen inside the command, not at start-up.
"""

from __future__ import annotations

import argparse
import importlib
import sys

from pytest_emrd.errors import EmrdError

#: Subcommand modules, in the order ``emrd --help`` lists them.
COMMANDS: tuple[str, ...] = ("render", "serve", "gate", "report", "validate", "bench")


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="emrd", description="pytest-emrd: Explore, Map, Remember, Decide benchmark tools."
    )
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for name in COMMANDS:
        try:
            module = importlib.import_module(f"pytest_emrd.cli.{name}")
        except ModuleNotFoundError as exc:
            if exc.name != f"pytest_emrd.cli.{name}":
                raise
            continue
        module.register(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    try:
        return int(args.func(args) or 0)
    except EmrdError as exc:
        print(f"emrd {args.command}: error: {exc}", file=sys.stderr)
        return 2
