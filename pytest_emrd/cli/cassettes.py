"""``emrd cassettes show FILE``.

``show`` prints a cassette as the plain vcrpy JSON cassette it holds (what ``xz -dc FILE``
prints), after checking it (bounded, schema and digest: docs/security.md). Exit status: 0
on success, 2 on an error.
"""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

HELP = "show a cassette as the vcrpy JSON it holds"
DESCRIPTION = __doc__.split("\n\n")[1]


def add_arguments(p: argparse.ArgumentParser) -> None:
    actions = p.add_subparsers(dest="action", required=True, metavar="ACTION")
    show = actions.add_parser("show", help="print a cassette as the vcrpy JSON it holds")
    show.add_argument("file", type=Path, help="cassette file (ep<NN>.json.xz)")


def run(args: argparse.Namespace) -> int:
    """``show`` (the only action)."""
    from pytest_emrd.cassette import FormatError, read_cassette
    from pytest_emrd.errors import CassetteError, ConfigError

    here = Path.cwd()  # under it, no folder on the way may be a symbolic link either
    root = here if here in Path(os.path.abspath(args.file)).parents else None
    try:
        _, text = read_cassette(args.file, root=root)  # checked: what is shown is what replays
    except OSError as exc:
        raise ConfigError(f"file={str(args.file)!r} cannot be read: {exc.strerror}") from None
    except FormatError as exc:
        raise CassetteError(
            f"file={str(args.file)!r} is not a replayable cassette: {exc}"
        ) from None
    sys.stdout.write(text)
    return 0
