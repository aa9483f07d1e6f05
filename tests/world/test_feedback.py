"""The shared feedback wording: execution outcome, reasons, Goto target, odometry line."""

from __future__ import annotations

import pytest
from hypothesis import given
from hypothesis import strategies as st

from pytest_emrd.errors import ConfigError
from pytest_emrd.trajectory import Pose
from pytest_emrd.world import VisibleObject, WorldPose
from pytest_emrd.world._feedback import (
    Action,
    ActionFailed,
    SemanticStep,
    choose_target,
    execute,
    observed_pose,
    room_table,
    term,
    with_pose,
)


def _refuse(action: Action) -> str:
    raise ActionFailed(f"{action.arg} is locked")


HANDLERS = {"Goto": lambda a: f": moved to {a.arg}_1", "Turn": lambda a: "", "Term": _refuse}


@pytest.mark.parametrize(
    ("text", "over", "expected"),
    [
        ("goto( Desk )", False, (True, "Goto(Desk) succeeded: moved to Desk_1.")),
        ("Turn(Left).", False, (True, "Turn(Left) succeeded.")),
        ("Term(Kitchen)", False, (False, "Term(Kitchen) failed: Kitchen is locked.")),
        ("Turn(Left)", True, (False, "Turn(Left) failed: the episode is over.")),
        (
            "walk\n  north",
            False,
            (False, "Action failed: could not read 'walk north'; use Goto(target), "
             "Turn(Left|Right|Around) or Term(room)."),
        ),
    ],
    ids=["goto-note", "turn", "handler-fails", "after-the-end", "unreadable"],
)  # fmt: skip
def test_execute_words_every_outcome(text: str, over: bool, expected: tuple[bool, str]) -> None:
    assert execute(text, HANDLERS, over=over) == expected


def test_term_reads_rooms_and_aliases_and_records_the_rest_as_other() -> None:
    rooms = room_table({"Room A": "Office"})
    assert term(rooms, Action("Term", "room_a")) == ("Office", ": the episode is over")
    assert term(rooms, Action("Term", "conference room"))[0] == "Conference Room"
    room, note = term(rooms, Action("Term", "Lobby"))
    assert room is None
    assert note == ": the episode is over; 'Lobby' is not one of the four rooms (recorded as Other)"


def test_an_alias_for_an_unknown_room_is_a_config_error() -> None:
    with pytest.raises(ConfigError, match=r"room_aliases\['Room A'\]='Garage'"):
        room_table({"Room A": "Garage"})


def _seen(*distances: float) -> tuple[VisibleObject, ...]:
    """``Desk_1``, ``Desk_2`` and ``Chair_1`` at ``distances``."""
    ids = ("Desk_1", "Desk_2", "Chair_1")
    return tuple(
        VisibleObject(i, i.split("_")[0], 0.0, d) for i, d in zip(ids, distances, strict=True)
    )


def test_goto_prefers_the_instance_then_the_nearest_of_the_type() -> None:
    assert choose_target("desk2", _seen(1.0, 3.0, 2.0), symbolic=True) == _seen(1.0, 3.0, 2.0)[1]
    assert choose_target("desk", _seen(3.0, 1.0, 2.0), symbolic=True) == _seen(3.0, 1.0, 2.0)[1]
    tie = choose_target("desk", _seen(2.0, 2.0, 2.0), symbolic=True)
    assert tie is not None and tie.object_id == "Desk_1"  # tie: by id
    assert choose_target("fridge", _seen(1.0, 1.0, 1.0), symbolic=True) is None


class _Backend(SemanticStep):
    """The shared Goto over a fixed view: ``Desk_1`` (1 m), ``Desk_2`` (3 m), ``Chair_1``."""

    def __init__(self, *, symbolic: bool, reachable: bool = True) -> None:
        self._steps, self._ended, self._symbolic = 0, False, symbolic
        self._rooms, self._reachable, self.reached = room_table(), reachable, ""

    def _in_view(self) -> tuple[VisibleObject, ...]:
        return _seen(1.0, 3.0, 2.0)

    def _reach(self, object_id: str) -> bool:
        self.reached = object_id
        return self._reachable

    def _turn(self, action: Action) -> str:
        return ""

    def _require(self) -> None:
        return None

    def _observe(self, success: bool, message: str) -> tuple[bool, str]:  # type: ignore[override]
        return success, message


def test_vision_goto_reads_types_only() -> None:
    backend = _Backend(symbolic=False)
    assert backend.step("Goto(Desk_2)") == (True, "Goto(Desk_2) succeeded.")
    assert backend.reached == "Desk_1"
    assert choose_target("desk2", _seen(1.0, 3.0, 2.0), symbolic=False) is None
    symbolic = _Backend(symbolic=True)
    assert symbolic.step("Goto(Desk_2)") == (True, "Goto(Desk_2) succeeded.")
    assert symbolic.reached == "Desk_2"
    assert symbolic.step("Goto(Desk)") == (True, "Goto(Desk) succeeded: moved to Desk_1.")


@pytest.mark.parametrize("symbolic", [True, False], ids=["symbolic", "vision"])
def test_goto_wording_names_ids_only_when_symbolic(symbolic: bool) -> None:
    texts = [
        _Backend(symbolic=symbolic).step("Goto(Sofa)")[1],
        _Backend(symbolic=symbolic, reachable=False).step("Goto(Desk)")[1],
        _Backend(symbolic=symbolic).step("Goto(Desk)")[1],
        _Backend(symbolic=symbolic).step("Goto()")[1],
    ]
    assert any("_1" in t for t in texts) is symbolic
    assert texts[3].startswith("Goto() failed: Goto needs a target: ")


def test_goto_failures_are_worded_for_the_agent() -> None:
    assert _Backend(symbolic=True).step("Goto(Sofa)") == (
        False,
        "Goto(Sofa) failed: no visible object matches 'Sofa'. Visible: Chair_1, Desk_1, Desk_2.",
    )
    assert _Backend(symbolic=False).step("Goto(Sofa)") == (
        False,
        "Goto(Sofa) failed: no object of type 'Sofa' is visible.",
    )
    assert _Backend(symbolic=False, reachable=False).step("Goto(Desk)") == (
        False,
        "Goto(Desk) failed: there is no free spot to stand at the nearest Desk.",
    )


@given(
    x=st.floats(-20, 20),
    z=st.floats(-20, 20),
    heading=st.sampled_from([0.0, 90.0, 180.0, 270.0]),
)
def test_odometry_line_never_shows_minus_zero(x: float, z: float, heading: float) -> None:
    spawn = WorldPose(x, z, heading)
    pose = observed_pose(spawn, WorldPose(x, z, heading))
    assert pose == Pose(0.0, 0.0, 0.0)
    assert with_pose("Done.", pose) == "Done. Pose: x=0.00 z=0.00 heading=0."
    text = with_pose("Done.", Pose(-0.004, 1.005, 90.0))
    assert text == "Done. Pose: x=0.00 z=1.00 heading=90."
