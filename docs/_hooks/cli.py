"""MkDocs hook: the ``emrd`` command's own ``--help`` text in place of :data:`MARKER`.

The CLI reference then cannot drift from the parser: every subcommand the console script
registers is printed with its options, as ``emrd COMMAND --help`` prints them.
"""

from __future__ import annotations

import argparse
import os

#: The line of a docs page the generated reference replaces.
MARKER = "<!-- emrd-help -->"


def _subcommands(parser: argparse.ArgumentParser) -> dict[str, argparse.ArgumentParser]:
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            return dict(action.choices)
    return {}


def emrd_help() -> str:
    """One section per ``emrd`` subcommand: its help as the console script prints it."""
    from pytest_emrd.cli import build_parser

    columns = os.environ.get("COLUMNS")
    os.environ["COLUMNS"] = "100"  # argparse wraps help to the terminal width
    try:
        parser = build_parser()
        sections = [f"```text\n{parser.format_help().rstrip()}\n```"]
        for name, sub in _subcommands(parser).items():
            help_text = sub.format_help().rstrip()
            sections.append(f"### `emrd {name}`\n\n```text\n{help_text}\n```")
    finally:
        if columns is None:
            os.environ.pop("COLUMNS")
        else:
            os.environ["COLUMNS"] = columns
    return "\n\n".join(sections)


def on_page_markdown(markdown: str, **_: object) -> str:
    """Replace :data:`MARKER` with :func:`emrd_help`."""
    if MARKER not in markdown:
        return markdown
    return markdown.replace(MARKER, emrd_help())
