"""JSON round-trip of the cross-stage dataclasses (pytest_emrd._serde, trajectory.py)."""

from __future__ import annotations

import dataclasses
import json

import pytest
from hypothesis import given
from hypothesis import strategies as st

from pytest_emrd._serde import from_dict, from_versioned_dict, to_dict
from pytest_emrd.agent import REPAIRS
from pytest_emrd.errors import ProtocolError
from pytest_emrd.trajectory import (
    EpisodeSpec,
    GroundTruth,
    GroundTruthObject,
    MapEntry,
    Pose,
    RoomOutline,
    Step,
    Trajectory,
    Usage,
)

finite = st.floats(-1e6, 1e6, allow_nan=False)
labels = st.text(min_size=1, max_size=12)


@st.composite
def trajectories(draw: st.DrawFn) -> Trajectory:
    objects = tuple(
        GroundTruthObject(f"Desk_{i}", "Desk", "Office", "salient", draw(finite), draw(finite))
        for i in range(draw(st.integers(0, 4)))
    )
    steps = tuple(
        Step(
            index=i + 1,
            pose=Pose(draw(finite), draw(finite), draw(st.floats(0, 359))),
            room="Office",
            visible_ids=tuple(o.object_id for o in objects),
            cognitive_map=tuple(
                MapEntry(draw(labels), "Desk", draw(finite), draw(finite), draw(st.none() | labels))
                for _ in range(draw(st.integers(0, 3)))
            ),
            action=draw(st.text(max_size=20)),
            success=draw(st.booleans()),
            feedback="ok",
            parse_error=draw(st.none() | st.text(max_size=10)),
            usage=Usage(draw(st.integers(0, 10**6)), draw(st.integers(0, 10**6))),
            repairs=draw(st.none() | st.lists(st.sampled_from(REPAIRS), unique=True).map(tuple)),
        )
        for i in range(draw(st.integers(0, 3)))
    )
    return Trajectory(
        spec=EpisodeSpec("scout", "baseline", "office", draw(st.integers(0, 99))),
        protocol="p",
        ground_truth=GroundTruth(
            objects, (RoomOutline("Office", ((0.0, 0.0), (1.0, 1.0))),), (), "Office"
        ),
        steps=steps,
        status=draw(st.sampled_from(["terminated", "budget", "errored"])),
        final_room="Office",
        chosen_room=draw(st.none() | st.just("Kitchen")),
    )


@given(trajectories())
def test_trajectory_round_trips_through_json(trajectory: Trajectory) -> None:
    data = json.loads(json.dumps(trajectory.to_dict()))
    assert Trajectory.from_dict(data) == trajectory


def test_unknown_field_is_an_error_naming_the_path() -> None:
    data = to_dict(Pose(1.0, 2.0, 90.0)) | {"yaw": 3}
    with pytest.raises(ProtocolError, match=r"Pose: unknown field\(s\) \['yaw'\]"):
        from_dict(Pose, data)


def test_integers_become_floats_where_the_field_is_a_float() -> None:
    assert from_dict(Pose, {"x": 1, "z": 2, "heading": 0}) == Pose(1.0, 2.0, 0.0)


@pytest.mark.parametrize("data", [{"schema_version": 0}, {}, []], ids=["old", "missing", "list"])
def test_other_schema_versions_are_refused_with_the_remedy(data: object) -> None:
    with pytest.raises(ProtocolError, match=r"schema_version=.* is not 1; re-run it"):
        from_versioned_dict(Pose, data, version=1, what="pose", remedy="re-run it")


@pytest.mark.parametrize("found", [1, 2])
def test_an_older_readable_schema_is_upgraded(found: int) -> None:
    data = {"x": 1.0, "z": 2.0, "heading": 0.0, "schema_version": found}

    @dataclasses.dataclass(frozen=True)
    class Versioned:
        x: float
        z: float
        heading: float
        schema_version: int = 2

    read = from_versioned_dict(Versioned, data, version=2, what="pose", remedy="-", older=(1,))
    assert read.schema_version == 2
    with pytest.raises(ProtocolError, match="schema_version=1 is not 2"):
        from_versioned_dict(Versioned, data | {"schema_version": 1}, version=2, what="pose",
                            remedy="-")  # fmt: skip


def test_a_schema_1_trajectory_reads_with_repairs_not_recorded() -> None:
    step = to_dict(Step(1, Pose(0.0, 0.0, 0.0), "Office", (), (), "Turn(Left)", True, "ok"))
    del step["repairs"]
    truth = GroundTruth((), (RoomOutline("Office", ((0.0, 0.0), (1.0, 1.0))),), (), "Office")
    data = Trajectory(EpisodeSpec("scout", "baseline", "office", 0), "p", truth, (), "budget",
                      "Office").to_dict() | {"schema_version": 1, "steps": [step]}  # fmt: skip
    read = Trajectory.from_dict(data)
    assert read.schema_version == 2 and read.steps[0].repairs is None


def test_episode_spec_seed_ignores_model_condition_and_variant() -> None:
    a = EpisodeSpec("scout", "baseline", "kitchen", 7)
    b = EpisodeSpec("gemini", "low_light", "kitchen", 7, variant="B1")
    assert a.seed == b.seed != EpisodeSpec("scout", "baseline", "office", 7).seed
    assert b.case_id == "gemini-low_light-B1-kitchen-ep07"
