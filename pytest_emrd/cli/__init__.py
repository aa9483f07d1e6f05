"""The ``emrd`` console script: one module per subcommand, each with its ``HELP`` line (and
optional ``DESCRIPTION``), ``add_arguments(parser)`` and ``run(args)``, which returns the exit
status; heavy imports happen inside ``run``, not at start-up."""

from __future__ import annotations

import argparse
import importlib
import sys
from pathlib import Path

from pytest_emrd.errors import ConfigError, EmrdError

__all__ = ["COMMANDS", "build_parser", "check_run_dirs", "main", "version_text"]

#: Subcommand modules, in the order ``emrd --help`` lists them (``_`` spelled ``-``).
COMMANDS: tuple[str, ...] = (
    "models",
    "check",
    "render",
    "serve",
    "gate",
    "thresholds",
    "report",
    "view",
    "cassettes",
    "validate",
    "thor_smoke",
)


def version_text() -> str:
    """``emrd 0.1.0 (protocol builtin-6+p3, reference agents ref-4)``: what cassettes apply.

    :returns: The version line ``emrd --version`` prints.
    """
    from pytest_emrd import __version__
    from pytest_emrd.agent import REFERENCE_VERSION
    from pytest_emrd.protocol import protocol_version

    return (
        f"emrd {__version__} (protocol {protocol_version()}, reference agents {REFERENCE_VERSION})"
    )


class _Version(argparse.Action):
    """``--version``: computed only when asked (it imports the world and the prompt)."""

    def __call__(self, parser: argparse.ArgumentParser, *args: object) -> None:
        print(version_text())
        parser.exit()


def build_parser() -> argparse.ArgumentParser:
    """The ``emrd`` parser with every subcommand of :data:`COMMANDS` registered.

    :returns: The parser; each subcommand sets ``func``.
    """
    parser = argparse.ArgumentParser(
        prog="emrd", description="pytest-emrd: Explore, Map, Remember, Decide benchmark tools."
    )
    parser.add_argument("--version", action=_Version, nargs=0, help="print the version and exit")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for name in COMMANDS:
        command = importlib.import_module(f"pytest_emrd.cli.{name}")
        p = sub.add_parser(
            name.replace("_", "-"),
            help=command.HELP,
            description=getattr(command, "DESCRIPTION", None),
        )
        command.add_arguments(p)
        p.set_defaults(func=command.run)
    return parser


def check_run_dirs(run_dirs: list[Path]) -> None:
    """A one-line :class:`ConfigError` for a RUN_DIR argument that is not a folder.

    :param run_dirs: The RUN_DIR arguments.
    :raises ConfigError: For the first that is not a folder.
    """
    for run_dir in (d for d in run_dirs if not d.is_dir()):
        file = run_dir.exists()
        raise ConfigError(
            f"RUN_DIR {run_dir} {'is a file, not a run directory' if file else 'does not exist'}"
            "; pass the folder a pytest run wrote (--emrd-results DIR, or one under .emrd/runs)"
            + ("; a thresholds file goes after --thresholds." if file else ".")
        )


#: The commands whose ``--out DIR`` picks where they write, named in a file system error.
_WRITES = ("view", "report", "render")


def main(argv: list[str] | None = None) -> int:
    """Run one command; an :class:`EmrdError` or a file system failure (full disk, read-only
    folder, a file where a folder belongs) ends it in one scrubbed line and exit status 2.

    :param argv: The arguments; None for ``sys.argv[1:]``.
    :returns: The exit status.
    """
    from pytest_emrd._scrub import install_log_scrub, scrub

    install_log_scrub()
    args = build_parser().parse_args(argv)
    try:
        return int(args.func(args) or 0)
    except EmrdError as exc:
        message = str(exc)
    except OSError as exc:
        from pytest_emrd._files import os_error_line

        message = os_error_line(
            exc,
            doing="read" if isinstance(exc, FileNotFoundError) else "write",
            option="--out DIR" if args.command in _WRITES else "",
        )
    print(f"emrd {args.command}: error: {scrub(message)}", file=sys.stderr)
    return 2
