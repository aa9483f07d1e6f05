"""MkDocs hook: the furniture catalogue as a table in place of :data:`MARKER`.

Each row is a kind of :data:`pytest_emrd.world.KINDS` with the rooms of the paper's office
(:func:`pytest_emrd.world.paper_office`) that hold it, so the page cannot drift from the code.
"""

from __future__ import annotations

from collections import Counter

#: The line of a docs page the generated table replaces.
MARKER = "<!-- emrd-catalogue -->"


def catalogue_table() -> str:
    """One Markdown row per catalogue kind: type, category, size, elevation and rooms.

    :returns: The table, header included.
    """
    from pytest_emrd.world import KINDS, paper_office

    rooms: dict[str, Counter[str]] = {name: Counter() for name in KINDS}
    for obj in paper_office().objects:
        kind = next(
            (
                k
                for k in KINDS.values()
                if (k.object_type, k.height) == (obj.object_type, obj.height)
            ),
            None,
        )
        if kind is not None:
            rooms[kind.name][obj.room] += 1
    lines = [
        "| kind | `objectType` | category | size w × d × h (m) | elevation (m) | rooms (count) |",
        "|---|---|---|---|---|---|",
    ]
    for kind in KINDS.values():
        where = ", ".join(f"{room} ({n})" for room, n in rooms[kind.name].items()) or "–"
        size = f"{kind.width:g} × {kind.depth:g} × {kind.height:g}"
        lines.append(
            f"| {kind.name} | `{kind.object_type}` | {kind.category} | {size} "
            f"| {kind.elevation:g} | {where} |"
        )
    return "\n".join(lines)


def on_page_markdown(markdown: str, **_: object) -> str:
    """Replace :data:`MARKER` with :func:`catalogue_table`."""
    if MARKER not in markdown:
        return markdown
    return markdown.replace(MARKER, catalogue_table())
