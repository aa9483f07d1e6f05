"""``emrd cassettes upgrade [DIR]``: rewrite old cassettes in the current format.

Every ``*.yaml.gz`` cassette under DIR (default ``./cassettes``), written in format
``emrd-cassette/1`` by an older pytest-emrd, is rewritten as ``.yaml.xz`` in the current
format (about a third smaller) without re-recording: each new file is checked to hold exactly
the same interactions before the old one is removed. Old files replay as they are; upgrading
is optional. Exit status: 0 when every file was upgraded (or none needed it), 2 on an error.
"""

from __future__ import annotations

import argparse
from pathlib import Path


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "cassettes",
        help="maintain cassette folders (upgrade old cassettes to the current format)",
        description=__doc__.split("\n\n")[1],
    )
    actions = p.add_subparsers(dest="action", required=True, metavar="ACTION")
    up = actions.add_parser("upgrade", help="rewrite *.yaml.gz cassettes as .yaml.xz, verified")
    up.add_argument("dir", nargs="?", type=Path, default=Path("cassettes"), help="cassette folder")
    up.set_defaults(func=_upgrade)


def _upgrade(args: argparse.Namespace) -> int:
    from pytest_emrd.cassette import upgrade
    from pytest_emrd.errors import ConfigError

    if not args.dir.is_dir():
        raise ConfigError(f"dir={str(args.dir)!r} is not a folder; give the cassette folder")
    count = before = after = 0
    for done in upgrade(args.dir):
        count, before, after = count + 1, before + done.old_bytes, after + done.new_bytes
    if not count:
        print(f"no format-1 cassettes (*.yaml.gz) under {args.dir}: nothing to upgrade")
        return 0
    print(
        f"upgraded {count} cassettes under {args.dir} to .yaml.xz: "
        f"{before / 1024:.1f} KB -> {after / 1024:.1f} KB ({after / before:.0%})"
    )
    return 0
