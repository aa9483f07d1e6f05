"""The scout's and prior's decisions on hand-made views (symbolic list, known poses)."""

from __future__ import annotations

import pytest

from pytest_emrd.trajectory import Pose

#: A dark kitchen: four sweep views from the spawn point, no doorway within sight.
DARK_KITCHEN = [
    [("Fridge_1", "Fridge", 0.0, 2.0), ("Sink_1", "Sink", 20.0, 1.5)],
    [("CounterTop_1", "CounterTop", 0.0, 3.0)],
    [],
    [("Stool_1", "Stool", 10.0, 2.5)],
]


def _sweep(driver, views) -> list[dict]:
    return [driver.see(v, Pose(0.0, 0.0, 90.0 * i)) for i, v in enumerate(views)]


def test_scout_repositions_when_no_doorway_is_in_sight(drive) -> None:
    scout = drive("scout")
    replies = _sweep(scout, DARK_KITCHEN)
    assert [r["action"] for r in replies] == ["Turn(Right)"] * 3 + ["Turn(Around)"]
    assert replies[-1]["reasoning"] == "Turning towards CounterTop_1."  # farthest from (0, 0)
    goto = scout.see([("CounterTop_1", "CounterTop", 0.0, 3.0)], Pose(0.0, 0.0, 90.0))
    assert goto["action"] == "Goto(CounterTop_1)"
    assert goto["reasoning"] == "Repositioning at CounterTop_1."
    arrived = scout.see([("CounterTop_1", "CounterTop", 0.0, 0.7)], Pose(2.3, 0.0, 90.0))
    assert arrived["action"] == "Turn(Right)", "a new sweep starts where it arrived"
    assert arrived["plan"]["sweeps"] == [[0.0, 0.0], [2.3, 0.0]]
    assert (arrived["plan"]["clears"], arrived["plan"]["moves"]) == (0, 1)


def test_scout_clears_the_room_before_an_unused_doorway(drive) -> None:
    """The kitchen is not complete: before leaving, the scout walks to the object farthest
    from where it swept among those within 3 m (the farthest it saw a doorway) of the
    doorway: the stool (the counter, farther, lies 6 m from the doorway)."""
    views = [*DARK_KITCHEN[:3], [*DARK_KITCHEN[3], ("Doorway_2", "Doorway", -5.0, 3.0)]]
    replies = _sweep(drive("scout"), views)
    assert replies[-1]["action"] == "Goto(Stool_1)"
    assert replies[-1]["plan"]["clears"] == 1


def test_scout_goes_through_an_unused_doorway_of_a_complete_room(drive) -> None:
    kitchen = [
        ("CounterTop_2", "CounterTop", -10.0, 2.0),
        ("CoffeeMachine_1", "CoffeeMachine", 5.0, 2.5),
        ("Microwave_1", "Microwave", 15.0, 2.0),
    ]
    views = [
        [*DARK_KITCHEN[0], *kitchen],
        *DARK_KITCHEN[1:3],
        [*DARK_KITCHEN[3], ("Doorway_2", "Doorway", -5.0, 3.0)],
    ]
    replies = _sweep(drive("scout"), views)
    assert replies[-1]["action"] == "Goto(Doorway_2)"
    assert (replies[-1]["plan"]["clears"], replies[-1]["plan"]["moves"]) == (0, 0)


def test_scout_with_nothing_in_sight_terminates(drive) -> None:
    replies = _sweep(drive("scout"), [[], [], [], []])
    assert replies[-1]["action"] == "Term(Office)"
    assert replies[-1]["reasoning"].startswith("No doorway left to try.")


@pytest.mark.parametrize(
    ("views", "chosen"),
    [
        ([[("DiningTable_1", "DiningTable", 0.0, 2.0)], [], [], []], "Office"),  # ties Entrance
        ([[], [], [("Fridge_1", "Fridge", 0.0, 2.0)], []], "Conference Room"),
        ([[], [], [], []], "Conference Room"),
    ],
    ids=["in-conference", "kitchen-seen-last", "nothing-in-view"],
)
def test_prior_looks_around_in_place_then_names_another_room(drive, views, chosen) -> None:
    """2 chairs in the Office, 8 in the Conference Room, 1 stool, 2 armchairs (Entrance)."""
    replies = _sweep(drive("prior"), views)
    assert [r["action"] for r in replies] == ["Turn(Right)"] * 3 + [f"Term({chosen})"]
    assert all(r["cognitive_map"] == {} for r in replies)
    assert "seats by the building overview" in replies[-1]["reasoning"]
