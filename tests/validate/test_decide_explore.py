"""Decide and Explore rows on hand-built trajectories (pass and fail cases)."""

from __future__ import annotations

import pytest

from pytest_emrd.rooms import ROOM_NAMES
from pytest_emrd.validate import exploration_checks, prior_checks, scout_decide_checks

OFFICE, CONFERENCE = ROOM_NAMES[0], ROOM_NAMES[1]


def test_prior_rows_pass_without_evidence(build, chairs) -> None:
    # Sweeps the Office (objects 1-3), names the Conference Room (objects 11-20).
    traj = build([(OFFICE, chairs(1, 2, 3), chairs(1, 2, 3))] * 3, chosen=CONFERENCE)
    rows = prior_checks([traj])
    assert [r.verdict for r in rows] == ["pass", "pass", "pass"]


def test_prior_rows_fail_when_the_chosen_room_was_seen(build, chairs) -> None:
    # Object 11 (Conference Room) seen through a doorway and kept in the map.
    traj = build([(OFFICE, chairs(1, 11), chairs(1, 11))] * 3, chosen=CONFERENCE)
    never, bias, glob = prior_checks([traj])
    assert never.verdict == "pass"
    assert (bias.verdict, glob.verdict) == ("fail", "fail")
    assert glob.data["fpsg_global"] == 0.5


def test_scout_rows_pass_when_it_chooses_a_room_it_mapped(build, chairs) -> None:
    room = chairs(*range(1, 11))
    traj = build([(OFFICE, room, room)], chosen=OFFICE)
    never, local = scout_decide_checks([traj])
    assert (never.verdict, local.verdict) == ("pass", "pass")
    assert local.data["fpsg_local"] == 1.0


def test_scout_rows_fail_when_it_names_an_unvisited_room(build, chairs) -> None:
    traj = build([(OFFICE, chairs(1), chairs(1))], chosen=CONFERENCE)
    never, local = scout_decide_checks([traj])
    assert (never.verdict, local.verdict) == ("fail", "fail")


def test_exploration_rows(build, chairs) -> None:
    everything = chairs(*range(1, 41))
    base = build([(OFFICE, everything, everything)] * 3 + [(OFFICE, [], everything)],
                 chosen=OFFICE)  # fmt: skip
    dark = build([(OFFICE, chairs(1), chairs(1))] * 6, condition="low_light", chosen=OFFICE)
    coverage, aec, te = exploration_checks([base], [dark])
    assert [coverage.verdict, aec.verdict, te.verdict] == ["pass", "pass", "pass"]
    assert te.data == {"te_low_light": 5.0, "te_baseline": 3.0}
    swapped = exploration_checks([dark], [base])
    # The dark scout maps the one chair it was shown: its coverage row still holds.
    assert [r.verdict for r in swapped] == ["pass", "fail", "fail"]


def test_coverage_row_counts_what_the_scout_was_shown(build, chairs) -> None:
    # Regression (issue 24's visibility): every object is discoverable from some standing
    # point (|G_base| = |E|), but the tour has only chairs 1-30 in view. A perfect scout
    # maps those 30: its AEC 0.75 is the planted coverage, not |G_base| / |E| = 1.
    shown = chairs(*range(1, 31))
    tour = build([(OFFICE, shown[:15], shown[:15]), (OFFICE, shown[15:], shown)],
                 chosen=OFFICE)  # fmt: skip
    dark = build([(OFFICE, [], [])] * 3, condition="low_light", chosen=OFFICE)
    coverage = exploration_checks([tour], [dark])[0]
    assert coverage.verdict == "pass"
    assert coverage.data == {"aec": 0.75, "shown": 0.75, "max_diff": 0.0, "discoverable": 1.0}


def test_coverage_row_fails_when_a_shown_object_is_not_counted(build, chairs) -> None:
    # Chair 30 was in view at step 1 and is gone from the terminal map.
    tour = build([(OFFICE, chairs(*range(1, 31)), chairs(*range(1, 31))),
                  (OFFICE, [], chairs(*range(1, 30)))], chosen=OFFICE)  # fmt: skip
    dark = build([(OFFICE, [], [])] * 3, condition="low_light", chosen=OFFICE)
    coverage = exploration_checks([tour], [dark])[0]
    assert coverage.verdict == "fail"
    assert coverage.data["max_diff"] == pytest.approx(1 / 40)
