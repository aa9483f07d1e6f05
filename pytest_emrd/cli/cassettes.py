"""``emrd cassettes show FILE`` and ``emrd cassettes upgrade [DIR]``.

``show`` prints a cassette as the plain vcrpy JSON cassette it holds (what ``xz -dc FILE``
prints), after checking its digest. ``upgrade`` converts, once, every cassette under DIR
(default ``./cassettes``) that an older pytest-emrd wrote (``*.yaml.gz``, ``*.yaml.xz``)
into a vcrpy cassette (``*.json.xz``), without re-recording: each new file is checked to
hold exactly the same interactions before the old one is removed. Exit status: 0 on
success (nothing to convert included), 2 on an error.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "cassettes",
        help="show a cassette; convert the cassettes of older releases",
        description=__doc__.split("\n\n")[1],
    )
    actions = p.add_subparsers(dest="action", required=True, metavar="ACTION")
    show = actions.add_parser("show", help="print a cassette as the vcrpy JSON it holds")
    show.add_argument("file", type=Path, help="cassette file (ep<NN>.json.xz)")
    show.set_defaults(func=_show)
    up = actions.add_parser("upgrade", help="convert old cassettes to vcrpy cassettes, verified")
    up.add_argument("dir", nargs="?", type=Path, default=Path("cassettes"), help="cassette folder")
    up.set_defaults(func=_upgrade)


def _show(args: argparse.Namespace) -> int:
    from pytest_emrd.cassette import FormatError, decode, decompress
    from pytest_emrd.errors import CassetteError, ConfigError

    try:
        blob = args.file.read_bytes()
        decode(blob)  # the digest is checked: what is shown is what replays
    except OSError as exc:
        raise ConfigError(f"file={str(args.file)!r} cannot be read: {exc.strerror}") from None
    except FormatError as exc:
        raise CassetteError(
            f"file={str(args.file)!r} is not a replayable cassette: {exc}"
        ) from None
    sys.stdout.write(decompress(blob))
    return 0


def _upgrade(args: argparse.Namespace) -> int:
    from pytest_emrd.cassette import upgrade
    from pytest_emrd.errors import ConfigError

    if not args.dir.is_dir():
        raise ConfigError(f"dir={str(args.dir)!r} is not a folder; give the cassette folder")
    count = before = after = 0
    for done in upgrade(args.dir):
        count, before, after = count + 1, before + done.old_bytes, after + done.new_bytes
    if not count:
        print(f"no old cassettes (*.yaml.gz, *.yaml.xz) under {args.dir}: nothing to upgrade")
        return 0
    print(
        f"upgraded {count} cassettes under {args.dir} to vcrpy cassettes (.json.xz): "
        f"{before / 1024:.1f} KB -> {after / 1024:.1f} KB, same interactions"
    )
    return 0
