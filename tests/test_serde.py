"""JSON round-trip of the cross-stage dataclasses (pytest_emrd._serde, trajectory.py)."""

from __future__ import annotations

import dataclasses
import enum
import importlib
import inspect
import json
import math
import pkgutil
import typing
from pathlib import Path, PurePosixPath
from typing import Any

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import pytest_emrd
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
from pytest_emrd.world._model import View

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


# --- to_dict's per-class writers against the generic recursion they replaced -----------------


def _oracle(obj: Any) -> Any:
    """The generic recursion ``to_dict`` was before its writers were compiled per class."""
    if dataclasses.is_dataclass(obj) and not isinstance(obj, type):
        return {f.name: _oracle(getattr(obj, f.name)) for f in dataclasses.fields(obj)}
    if isinstance(obj, tuple | list):
        return [_oracle(v) for v in obj]
    if isinstance(obj, dict):
        return {str(k): _oracle(v) for k, v in obj.items()}
    if isinstance(obj, frozenset | set):
        return sorted(_oracle(v) for v in obj)
    return obj


def _writes_as_the_oracle(obj: Any) -> None:
    new, old = to_dict(obj), _oracle(obj)
    assert json.dumps(new, default=repr) == json.dumps(old, default=repr)  # the bytes stored
    assert repr(new) == repr(old)  # and the values: list vs tuple, -0.0, nan, key order


def _package_dataclasses() -> list[type]:
    found = {}
    for info in pkgutil.walk_packages(pytest_emrd.__path__, "pytest_emrd."):
        if not info.name.endswith("__main__"):
            module = importlib.import_module(info.name)
            for value in vars(module).values():
                if inspect.isclass(value) and dataclasses.is_dataclass(value):
                    found[f"{value.__module__}.{value.__qualname__}"] = value
    return [found[name] for name in sorted(found)]


class _Colour(enum.Enum):
    RED = "red"


class _Level(enum.IntEnum):
    LOW = 1


scalars = (
    st.none()
    | st.booleans()
    | st.integers()
    | st.floats()  # nan, inf, -0.0 included
    | st.sampled_from([-0.0, math.nan, math.inf, -math.inf, _Colour.RED, _Level.LOW])
    | st.text(max_size=5)
    | st.builds(PurePosixPath, st.text(max_size=5))
)
values = st.recursive(
    scalars,
    lambda inner: (
        st.lists(inner, max_size=3)
        | st.lists(inner, max_size=3).map(tuple)
        | st.dictionaries(st.integers() | st.text(max_size=3) | st.booleans(), inner, max_size=3)
        | st.frozensets(st.integers(), max_size=3)
        | st.builds(Pose, st.floats(), st.floats(), st.floats())
    ),
    max_leaves=12,
)


# from_type(Path) alone builds only Path(): fields typed Path get relative and absolute paths
_PATH_TEXT = r"/?[a-z]{1,3}(/[a-z.]{1,3}){0,2}"
st.register_type_strategy(Path, st.builds(Path, st.from_regex(_PATH_TEXT, fullmatch=True)))


# A rendered view is carried as it is (pixels and JPEG made on first use): any small one.
st.register_type_strategy(
    View,
    st.builds(
        View.of,
        st.integers(0, 255).map(lambda v: np.full((2, 2, 3), v, dtype=np.uint8)),
        st.integers(1, 95),
    ),
)


def _mentions_any(hint: Any) -> bool:
    return hint is Any or any(map(_mentions_any, typing.get_args(hint)))


def _instances(cls: type) -> st.SearchStrategy[Any]:
    """Instances of ``cls`` from its type hints, any JSON-ish value where a hint says Any."""
    try:
        hints = typing.get_type_hints(cls)
    except NameError:
        return st.from_type(cls)
    loose = {f.name: values for f in dataclasses.fields(cls) if _mentions_any(hints[f.name])}
    return st.builds(cls, **loose) if loose else st.from_type(cls)


#: Dataclasses hypothesis cannot build from their hints, and why (each part of them is covered).
NOT_GENERATED = {
    "GateMetric": "a field typed by a Protocol that is not runtime-checkable",
    "Run": "holds a pytest Config",
    "CassetteData": "holds vcrpy Requests",
    "ModelConfig": "validates its provider name",
    "Registry": "validates its models' provider names",
    "_Probe": "validates its model's provider name",
    "Check": "validates its verdict",
    "ValidationReport": "validates its checks' verdicts",
    "Plan": "validates its episode count",
    "IdTable": "validates that its ids are one to one",
    "Report": "too large to generate in time (its sections and tables are generated)",
}
PACKAGE_DATACLASSES = _package_dataclasses()


def test_every_dataclass_left_out_exists() -> None:
    names = {cls.__qualname__ for cls in PACKAGE_DATACLASSES}
    assert set(NOT_GENERATED) <= names and len(names) > 100


@pytest.mark.parametrize(
    "cls",
    [cls for cls in PACKAGE_DATACLASSES if cls.__qualname__ not in NOT_GENERATED],
    ids=lambda cls: cls.__qualname__,
)
@settings(max_examples=10, suppress_health_check=[HealthCheck.data_too_large])
@given(data=st.data())
def test_every_package_dataclass_is_written_as_the_generic_recursion_wrote_it(
    cls: type, data: st.DataObject
) -> None:
    _writes_as_the_oracle(data.draw(_instances(cls)))


@dataclasses.dataclass(frozen=True)
class _Loose:
    """Fields whose values the hints do not pin down, and a hint out of reach."""

    anything: Any
    maybe: tuple[float, ...] | None
    pairs: tuple[tuple[float, float], ...]
    keyed: dict[Any, Any]
    tags: frozenset[str]
    where: Path
    colour: _Colour
    hidden: typing.ClassVar[int] = 3


@dataclasses.dataclass(frozen=True)
class _Wider(_Loose):
    extra: float = -0.0


@dataclasses.dataclass(frozen=True)
class _Single:
    only: Any


@dataclasses.dataclass(frozen=True)
class _Empty:
    pass


@given(
    values,
    st.none() | st.lists(st.floats(), max_size=3).map(tuple),
    st.dictionaries(
        st.integers() | st.text(max_size=3) | st.booleans() | st.none(), values, max_size=3
    ),
)
def test_generated_objects_are_written_as_the_generic_recursion_wrote_them(
    anything: Any, maybe: tuple[float, ...] | None, keyed: dict[Any, Any]
) -> None:
    loose = _Loose(anything, maybe, ((0.0, -0.0), (math.nan, math.inf)), keyed,
                   frozenset({"b", "a"}), Path("a/b"), _Colour.RED)  # fmt: skip
    wider = _Wider(**vars(loose), extra=math.nan)
    for obj in (loose, wider, _Single(anything), _Empty(), [loose, (wider,)], {1: loose},
                {loose.tags}, Pose, anything, _out_of_reach(anything)):  # fmt: skip
        _writes_as_the_oracle(obj)


def _out_of_reach(value: Any) -> Any:
    """A dataclass whose hints name a class ``get_type_hints`` cannot see."""

    class Local:
        pass

    @dataclasses.dataclass(frozen=True)
    class Hidden:
        local: Local | None
        value: Any
        number: float

    return Hidden(None, value, -0.0)


@pytest.mark.slow
@pytest.mark.parametrize("model", ["scout", "mimic"])
def test_a_replayed_committed_episode_is_written_as_the_generic_recursion_wrote_it(
    model: str,
) -> None:
    """A committed episode (mimic's replies are the malformed ones), its metrics and head."""
    from pytest_emrd.agent import load_registry
    from pytest_emrd.episode import protocol_version
    from pytest_emrd.metrics import episode_metrics
    from pytest_emrd.run import EpisodeHead
    from tests._episodes import agent_runner, run_with_cassette

    spec = EpisodeSpec(model, "baseline", "office", 3, modality="both")
    run = run_with_cassette(
        spec,
        agent_runner(load_registry()),
        cassettes=Path(__file__).resolve().parents[1] / "cassettes",
        protocol=protocol_version("builtin"),
        record_mode="none",
    )
    trajectory = run.trajectory
    assert trajectory.status != "errored", trajectory.error
    assert len(trajectory.steps) > 10
    head = EpisodeHead.of(trajectory, session="s", recorded=False, frame_drift=0, seconds=1.5)
    for obj in (trajectory, episode_metrics(trajectory), head):
        _writes_as_the_oracle(obj)
