"""EpisodeMetrics: JSON round-trip, errored episodes, and no NaN leaks on odd episodes."""

from __future__ import annotations

import json
import math
from collections.abc import Callable
from dataclasses import fields

import pytest
from hypothesis import given
from hypothesis import strategies as st

from pytest_emrd.errors import ProtocolError
from pytest_emrd.metrics import EpisodeMetrics, episode_metrics
from pytest_emrd.rooms import CONFERENCE, OFFICE
from pytest_emrd.trajectory import GroundTruthObject, Trajectory

MakeObj = Callable[..., GroundTruthObject]
MakeTraj = Callable[..., Trajectory]


def test_json_round_trip(small_grid_metrics: list[EpisodeMetrics]) -> None:
    for m in small_grid_metrics[:5]:
        data = json.loads(json.dumps(m.to_dict()))
        assert EpisodeMetrics.from_dict(data) == m


def test_stale_schema_is_rejected(small_grid_metrics: list[EpisodeMetrics]) -> None:
    data = small_grid_metrics[0].to_dict() | {"schema_version": 0}
    with pytest.raises(ProtocolError, match="schema_version=0"):
        EpisodeMetrics.from_dict(data)


def test_errored_episode_has_no_scores_and_says_why(make_obj: MakeObj, make_traj: MakeTraj) -> None:
    m = episode_metrics(make_traj([make_obj("Desk_1")], [], status="errored", error="drift"))
    assert m.errored and m.aec is None and m.te is None and m.memory_strength is None
    assert m.reasons["aec"] == "episode errored: drift"


def test_parse_failures_are_counted_and_keep_the_map(
    make_obj: MakeObj, make_traj: MakeTraj
) -> None:
    held = {"d": ("Desk", 0.0, 0.0)}
    traj = make_traj([make_obj("Desk_1")], [(OFFICE, ["Desk_1"], held), (OFFICE, [], {})],
                     parse_errors=[2])  # fmt: skip
    m = episode_metrics(traj)
    assert m.parse_failures == 1 and m.aec == 1.0


def _no_nan(value: object) -> bool:
    if isinstance(value, float):
        return not math.isnan(value)
    if isinstance(value, tuple | list):
        return all(_no_nan(v) for v in value)
    if isinstance(value, dict):
        return all(_no_nan(v) for v in value.values())
    return True


step = st.tuples(
    st.sampled_from([OFFICE, CONFERENCE]),
    st.sets(st.sampled_from(["Desk_1", "Desk_2", "Chair_1"])),
    st.dictionaries(
        st.sampled_from(["a", "b", "c", "d"]),
        st.tuples(
            st.sampled_from(["Desk", "Chair", "Sofa", ""]), st.floats(-10, 10), st.floats(-10, 10)
        ),
        max_size=4,
    ),
)


@given(st.lists(step, max_size=6), st.sampled_from([None, OFFICE, CONFERENCE]), st.integers(0, 3))
def test_no_nan_leaks_on_empty_single_and_odd_episodes(
    make_obj: MakeObj,
    make_traj: MakeTraj,
    steps: list[tuple[str, set[str], dict[str, tuple[str, float, float]]]],
    chosen: str | None,
    n_objects: int,
) -> None:
    truth = [
        make_obj("Desk_1", x=1),
        make_obj("Desk_2", x=4),
        make_obj("Chair_1", CONFERENCE, 2, 6),
    ]
    truth = truth[:n_objects]
    ids = {o.object_id for o in truth}
    cleaned = [(room, sorted(v & ids), cog) for room, v, cog in steps]
    m = episode_metrics(make_traj(truth, cleaned, chosen=chosen))
    for f in fields(m):
        assert _no_nan(getattr(m, f.name)), f.name
    for name in ("aec", "pa", "fpsg_local", "fpsg_global", "sir"):
        value = getattr(m, name)
        assert value is None or 0.0 <= value <= 1.0, name
        if value is None and steps:
            assert name in m.reasons, name
