"""Wall pieces: every room side split where neighbours meet, shared pieces paired."""

from __future__ import annotations

import math

from hypothesis import given
from hypothesis import strategies as st

from pytest_emrd.rooms import CONFERENCE, ENTRANCE, KITCHEN, OFFICE
from pytest_emrd.world import Layout, Room
from pytest_emrd.world.thor._house import WallPiece, wall_pieces


def _by_room(pieces: tuple[WallPiece, ...], n: int) -> list[WallPiece]:
    return [p for p in pieces if p.room == n]


def test_kitchen_north_side_is_split_where_office_and_conference_meet(layout: Layout) -> None:
    kitchen_north = [p for p in _by_room(wall_pieces(layout), 3) if p.axis == "x" and p.z0 == 4.0]
    assert [(p.x0, p.x1, p.neighbour) for p in kitchen_north] == [(0.0, 4.0, 1), (4.0, 5.0, 2)]


def test_ids_follow_procthor_wall_naming(layout: Layout) -> None:
    ids = {p.wall_id for p in wall_pieces(layout)}
    assert "wall|1|4.00|4.00|4.00|8.00" in ids  # Office east = Conference west
    assert "wall|2|4.00|4.00|4.00|8.00" in ids
    assert len(ids) == len(wall_pieces(layout))


def test_offset_along_a_piece_is_measured_from_its_first_point() -> None:
    piece = WallPiece(1, 4.0, 8.0, 4.0, 4.0, 2)  # runs south
    assert piece.offset_of(4.0, 7.0) == 1.0
    assert piece.offset_of(4.5, 7.0) is None
    assert piece.offset_of(4.0, 3.0) is None


def _check_tiling(layout: Layout) -> None:
    pieces = wall_pieces(layout)
    for n, room in enumerate(layout.rooms, start=1):
        perimeter = 2 * (room.x1 - room.x0 + room.z1 - room.z0)
        assert math.isclose(sum(p.length for p in _by_room(pieces, n)), perimeter)
    index = {(p.room, p.position_id): p for p in pieces}
    for p in pieces:
        if p.neighbour is None:
            continue
        twin = index[(p.neighbour, p.position_id)]
        assert twin.neighbour == p.room
        assert (twin.x0, twin.z0, twin.x1, twin.z1) == (p.x1, p.z1, p.x0, p.z0)


split = st.integers(min_value=2, max_value=8).map(lambda k: k * 0.5)


@given(top=split, bottom=split, middle=split)
def test_any_two_by_two_office_tiles_into_paired_pieces(
    top: float, bottom: float, middle: float
) -> None:
    width, depth = 10.0, 10.0
    layout = Layout(
        seed=0,
        width=width,
        depth=depth,
        rooms=(
            Room(OFFICE, 0.0, middle, top, depth),
            Room(CONFERENCE, top, middle, width, depth),
            Room(KITCHEN, 0.0, 0.0, bottom, middle),
            Room(ENTRANCE, bottom, 0.0, width, middle),
        ),
        doorways=(),
        objects=(),
    )
    _check_tiling(layout)
