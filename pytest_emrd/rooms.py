"""The four rooms of the EMRD office: names, slugs and the paper's letter codes.

Shared by every stage (world, agent, metrics, report) so that a room is spelled one way.
"""

from __future__ import annotations

from typing import Final

OFFICE: Final = "Office"
CONFERENCE: Final = "Conference Room"
KITCHEN: Final = "Kitchen"
ENTRANCE: Final = "Entrance"

#: Canonical room names, in the paper's Figure 1 reading order (top-left first).
ROOM_NAMES: Final[tuple[str, ...]] = (OFFICE, CONFERENCE, KITCHEN, ENTRANCE)

#: Slugs used in test ids, cassette paths and CLI options.
ROOM_SLUGS: Final[dict[str, str]] = {
    OFFICE: "office",
    CONFERENCE: "conference",
    KITCHEN: "kitchen",
    ENTRANCE: "entrance",
}
SLUG_ROOMS: Final[dict[str, str]] = {slug: name for name, slug in ROOM_SLUGS.items()}

#: Letter codes of the paper's focal-point tables; ``X`` is anything else (incl. no Term).
ROOM_LETTERS: Final[dict[str, str]] = {CONFERENCE: "C", OFFICE: "O", KITCHEN: "K", ENTRANCE: "E"}
OTHER_LETTER: Final = "X"
FOCAL_COLUMNS: Final[tuple[str, ...]] = ("C", "O", "K", "E", "X")


def room_letter(room: str | None) -> str:
    """The focal-point column of a chosen room (``X`` for ``None`` or an unknown room)."""
    return ROOM_LETTERS.get(room or "", OTHER_LETTER)
