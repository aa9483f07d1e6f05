"""Focal-point distribution, consensus and the FPSG table row."""

from __future__ import annotations

from collections.abc import Callable

import pytest

from pytest_emrd.metrics import EpisodeMetrics, consensus, focal_distribution, fpsg
from pytest_emrd.rooms import CONFERENCE, ENTRANCE, KITCHEN, OFFICE
from pytest_emrd.trajectory import GroundTruthObject, Trajectory

MakeObj = Callable[..., GroundTruthObject]
MakeTraj = Callable[..., Trajectory]


def _choices(make_traj: MakeTraj, spawn: str, chosen: list[str | None]) -> list[Trajectory]:
    return [make_traj([], [(spawn, [], {})], chosen=c, spawn=spawn, episode=i)
            for i, c in enumerate(chosen)]  # fmt: skip


def test_focal_distribution_by_spawn(make_traj: MakeTraj) -> None:
    trajs = _choices(make_traj, CONFERENCE, [CONFERENCE, CONFERENCE, ENTRANCE, None]) + _choices(
        make_traj, OFFICE, [KITCHEN, OFFICE]
    )
    dist = focal_distribution(trajs)
    assert list(dist.by_spawn) == ["conference", "office"]
    row = dist.by_spawn["conference"]
    assert row.counts == {"C": 2, "O": 0, "K": 0, "E": 1, "X": 1}
    assert row.fractions["C"] == 0.5 and row.fractions["X"] == 0.25
    assert dist.overall.n == 6
    assert sum(dist.overall.fractions.values()) == pytest.approx(1.0)


def test_errored_episodes_are_excluded_and_counted(make_traj: MakeTraj) -> None:
    ok = _choices(make_traj, OFFICE, [OFFICE])
    bad = make_traj([], [(OFFICE, [], {})], status="errored", chosen=OFFICE, error="timeout")
    dist = focal_distribution([*ok, bad])
    assert (dist.overall.n, dist.excluded) == (1, 1)
    assert fpsg([*ok, bad]).excluded == 1


def test_consensus_takes_the_modal_room_not_other(make_traj: MakeTraj) -> None:
    trajs = _choices(make_traj, OFFICE, [None, None, None, ENTRANCE, ENTRANCE, KITCHEN])
    res = consensus(trajs)
    assert (res.letter, res.share, res.n) == ("E", pytest.approx(2 / 6), 6)


@pytest.mark.parametrize(
    ("chosen", "letter", "share"),
    [([], None, None), ([None, None], None, 0.0), ([CONFERENCE, ENTRANCE], "C", 0.5)],
    ids=["no-episode", "never-chose", "tie-goes-to-C-first"],
)
def test_consensus_edge_cases(
    make_traj: MakeTraj, chosen: list[str | None], letter: str | None, share: float | None
) -> None:
    res = consensus(_choices(make_traj, OFFICE, chosen))
    assert (res.letter, res.share) == (letter, share)


def test_fpsg_summary_row(small_grid_metrics: list[EpisodeMetrics]) -> None:
    row = fpsg(small_grid_metrics)
    chose = [m for m in small_grid_metrics if m.never_visited is not None]
    assert row.runs == len(small_grid_metrics)
    assert row.never_visited == pytest.approx(sum(m.never_visited for m in chose) / len(chose))
    assert row.local_mean is not None and row.global_mean is not None
    assert 0.0 <= row.global_mean <= row.local_mean <= 1.0


def test_fpsg_summary_without_choices(make_traj: MakeTraj) -> None:
    row = fpsg(_choices(make_traj, OFFICE, [None]))
    assert (row.never_visited, row.any_bias, row.local_mean, row.local_sd) == (None,) * 4


def test_other_is_split_into_another_room_and_no_term(make_traj: MakeTraj) -> None:
    """X = a Term naming something outside the four rooms, or no Term at all (budget)."""
    named = make_traj([], [(OFFICE, [], {})], chosen=None, spawn=OFFICE)  # Term(Lobby)
    budget = make_traj([], [(OFFICE, [], {})], chosen=None, spawn=OFFICE, status="budget")
    kept = make_traj([], [(OFFICE, [], {})], chosen=OFFICE, spawn=OFFICE, episode=2)
    row = focal_distribution([named, budget, kept]).overall
    assert row.counts["X"] == 2 and (row.named_other, row.no_term) == (1, 1)
    assert (row.chose_spawn, row.spawn_share) == (1, pytest.approx(1 / 3))


def test_spawn_room_share_worked_example_appendix_f(make_traj: MakeTraj) -> None:
    """Appendix F's per-spawn table: 16 + 1 + 11 + 13 = 41 of 81 chose their spawn room."""
    rows = {
        CONFERENCE: [CONFERENCE] * 16 + [KITCHEN] + [ENTRANCE] * 4,
        OFFICE: [CONFERENCE] * 2 + [KITCHEN] * 13 + [ENTRANCE] * 4 + [OFFICE],
        KITCHEN: [CONFERENCE] * 4 + [KITCHEN] * 11 + [ENTRANCE] + [OFFICE] * 4,
        ENTRANCE: [KITCHEN] * 6 + [ENTRANCE] * 13 + [OFFICE],
    }
    trajs = [t for spawn, chosen in rows.items() for t in _choices(make_traj, spawn, chosen)]
    dist = focal_distribution(trajs)
    assert (dist.overall.chose_spawn, dist.overall.n) == (41, 81)
    assert round(100 * dist.overall.spawn_share, 1) == 50.6
    assert dist.by_spawn["conference"].spawn_share == pytest.approx(16 / 21)
    assert focal_distribution([]).overall.spawn_share is None
