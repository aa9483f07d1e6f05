"""What each room contains: the per-room recipes of the layout generator.

Office: 3-4 desks against the walls, each with a chair in front, 2-3 of them with a laptop;
1-2 shelving units; 2 plants. Conference Room: one long table in the middle with four chairs
down each side, a television on the wall at one end of the table. Kitchen: a fridge, two
counters (a sink and a coffee machine on one, a microwave on the other), a stool.
Entrance: a reception desk, two armchairs, a plant (the exit door is structural, see
:mod:`pytest_emrd.world._layout`). Big items are placed first; an item that finds no free
spot after :data:`~pytest_emrd.world._planner.CANDIDATES` tries is left out.
"""

from __future__ import annotations

from pytest_emrd.rooms import CONFERENCE, ENTRANCE, KITCHEN, OFFICE
from pytest_emrd.world._catalog import KINDS
from pytest_emrd.world._model import Room
from pytest_emrd.world._planner import Member, Planner, Unit

TABLE_LENGTHS = (3.2, 3.04, 2.8, 2.64)
"""Conference table lengths tried, longest first (multiples of 0.08 m: chair slots stay on
the centimetre grid)."""
COUNTER_LENGTHS = (1.6, 1.8, 2.0, 2.2)


def _single(kind: str, access: float, *, around: bool = False) -> Unit:
    k = KINDS[kind]
    return Unit((Member(kind),), k.width, k.depth, access, around)


def furnish(planner: Planner, rooms: dict[str, Room]) -> None:
    """Fill every room, in the fixed order that keeps generation deterministic."""
    _office(planner, rooms[OFFICE])
    _conference(planner, rooms[CONFERENCE])
    _kitchen(planner, rooms[KITCHEN])
    _entrance(planner, rooms[ENTRANCE])


def _desk_unit(with_laptop: bool, laptop_u: float) -> Unit:
    desk, chair = KINDS["Desk"], KINDS["Chair"]
    depth = desk.depth + 0.05 + chair.depth
    desk_v = -depth / 2 + desk.depth / 2
    members = [
        Member("Desk", v=desk_v),
        Member("Chair", v=depth / 2 - chair.depth / 2, turn=180.0),
    ]
    if with_laptop:
        members.append(Member("Laptop", u=laptop_u, v=round(desk_v + 0.1, 2)))
    return Unit(tuple(members), desk.width, round(depth, 2), 0.7)


def _office(p: Planner, room: Room) -> None:
    rng = p.rng
    for _ in range(rng.integer(1, 2)):
        p.against_wall(room, _single("ShelvingUnit", 0.8))
    n_desks = rng.integer(3, 4)
    n_laptops = min(rng.integer(2, 3), n_desks)
    laptops = set(rng.shuffled(range(n_desks))[:n_laptops])
    for i in range(n_desks):
        laptop_u = round(rng.uniform(-0.4, 0.4), 2)
        p.against_wall(room, _desk_unit(i in laptops, laptop_u))
    for _ in range(2):
        p.against_wall(room, _single("HousePlant", 0.5))


def _table_unit(length: float) -> Unit:
    table, chair = KINDS["DiningTable"], KINDS["Chair"]
    offset = table.depth / 2 + 0.05 + chair.depth / 2
    members = [Member("DiningTable", width=length)]
    for side, turn in ((offset, 180.0), (-offset, 0.0)):
        for i in range(4):
            u = round(-length / 2 + length / 8 + i * length / 4, 2)
            members.append(Member("Chair", u=u, v=side, turn=turn))
    return Unit(tuple(members), length, round(2 * offset + chair.depth, 2), 0.75, around=True)


def _conference(p: Planner, room: Room) -> None:
    along_x = (room.x1 - room.x0) >= (room.z1 - room.z0)
    rotations = (0.0, 180.0) if along_x else (90.0, 270.0)
    for length in TABLE_LENGTHS:
        if p.free(room, _table_unit(length), rotations, spread=0.6):
            break
    p.against_wall(room, _single("Television", 1.0), "EW" if along_x else "NS")


def _counter_unit(length: float, items: tuple[Member, ...]) -> Unit:
    counter = KINDS["CounterTop"]
    return Unit((Member("CounterTop", width=length), *items), length, counter.depth, 0.9)


def _kitchen(p: Planner, room: Room) -> None:
    rng = p.rng
    p.against_wall(room, _single("Fridge", 0.9))
    length = rng.choice(COUNTER_LENGTHS)
    sink_side = rng.choice((-1.0, 1.0))
    items = (
        Member("Sink", u=sink_side * length / 4),
        Member("CoffeeMachine", u=-sink_side * length / 4, v=0.1),
    )
    p.against_wall(room, _counter_unit(length, items))
    length = rng.choice(COUNTER_LENGTHS)
    micro_u = round(rng.uniform(-(length / 2 - 0.4), length / 2 - 0.4), 2)
    p.against_wall(room, _counter_unit(length, (Member("Microwave", u=micro_u, v=0.05),)))
    p.free(room, _single("Stool", 0.45, around=True), (0.0, 90.0, 180.0, 270.0))


def _entrance(p: Planner, room: Room) -> None:
    p.against_wall(room, _single("ReceptionDesk", 1.0))
    for _ in range(2):
        p.against_wall(room, _single("ArmChair", 0.7))
    p.against_wall(room, _single("HousePlant", 0.5))
