"""The mimic family: knobs from the name, replies malformed as planted, planted behaviour kept
apart from the walk (paired episodes), determinism."""

from __future__ import annotations

import math
import re

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from pytest_emrd.agent import load_registry, parse_reply
from pytest_emrd.episode import run_episode
from pytest_emrd.errors import ConfigError, ProtocolError
from pytest_emrd.metrics import canonical_type, rigid_fit
from pytest_emrd.reference._malform import FAILING, REPAIRABLE, malform, read_state, render
from pytest_emrd.reference._phrasing import (
    HALLUCINATIONS,
    NUMBERING,
    PHRASES,
    label_for,
    type_word,
)
from pytest_emrd.trajectory import EpisodeSpec, Trajectory
from pytest_emrd.world import KINDS

CLEAN = "mimic-spawn-s0-p0-h0-q0-r0-a0-b0"
PLANTED_INVALID = re.compile(r"^(MoveAhead|Turn\(Back\)|Goto\(the .*\)|Goto\(nearest exit\))$")


@pytest.mark.parametrize(
    ("name", "planted"),
    [
        ("mimic-s0.3", {"sigma": 0.3}),
        ("mimic-spawn-p0.5-h0", {"frame": "spawn", "dup": 0.5, "halluc": 0.0}),
        ("mimic-q0.1-r1-a0.02", {"fail": 0.1, "repair": 1.0, "invalid": 0.02}),
        ("mimic-spawn-reckon", {"frame": "spawn", "odometry": "reckon"}),
    ],
)
def test_knobs_in_the_name_override_the_mimic_entry(name: str, planted: dict) -> None:
    config = load_registry().get(name)
    shipped = load_registry().get("mimic").planted
    assert config.planted == {**shipped, **planted}
    assert config.model_id.startswith(f"{name}@ref-")


@pytest.mark.parametrize(
    ("name", "message"),
    [
        pytest.param("mimic-p1.5", r"dup=1.5 must lie in \[0.0, 1.0\]", id="rate-above-1"),
        pytest.param("mimic-s9", r"sigma=9.0 must lie in \[0.0, 5.0\]", id="sigma-too-large"),
        pytest.param("mimic-p0.1-p0.2", "sets dup twice", id="knob-twice"),
        pytest.param("mimic-reckon-reckon", "sets odometry twice", id="word-twice"),
        pytest.param("mimic-x3", "mimic-<knobs>", id="unknown-knob"),
    ],
)
def test_bad_mimic_names_say_what_to_fix(name: str, message: str) -> None:
    with pytest.raises(ConfigError, match=message):
        load_registry().get(name)


STATE = {"key": "00ff", "nav": {"plan": {"phase": "sweep", "note": "it's // not a comment"}}}
BODY = {
    "observation": "I can see: office chair, TV.",
    "dedup_check": "2 new, 0 already in my map.",
    "cognitive_map": {
        "office chair": {"type": "chair", "room": "Office", "x": 1.25, "z": -3.5},
        "TV": {"type": "TV", "room": "Office", "x": 4.0, "z": 2.0},
    },
    "action": "Turn(Right)",
    "reasoning": "Sweeping the room (1/3).",
}


@pytest.mark.parametrize("kind", REPAIRABLE)
@pytest.mark.parametrize("u", [0.0, 0.5, 0.99])
def test_a_repairable_slip_is_read_and_named(kind: str, u: float) -> None:
    text = malform(render(STATE, BODY), kind, u)
    reply = parse_reply(text)
    assert reply.error is None and reply.repairs == (kind,)
    assert [e.label for e in reply.cognitive_map] == ["office chair", "TV"]
    assert read_state(text) == STATE


@pytest.mark.parametrize("kind", FAILING)
@pytest.mark.parametrize("u", [0.0, 0.5, 0.99])
@pytest.mark.parametrize("cmap", [BODY["cognitive_map"], {}], ids=["map", "empty-map"])
def test_damage_is_a_parse_failure_the_agent_still_reads(kind: str, u: float, cmap) -> None:
    text = malform(render(STATE, BODY | {"cognitive_map": cmap}), kind, u)
    reply = parse_reply(text)
    assert reply.error is not None and reply.action == ""
    assert read_state(text) == STATE


texts = st.text(st.characters(codec="utf-8", exclude_categories=("Cs",)), max_size=12)
entries = st.fixed_dictionaries({"type": texts, "x": st.floats(-50, 50), "z": st.floats(-50, 50)})


@given(
    state=st.dictionaries(texts, st.none() | st.booleans() | texts | st.integers(), max_size=4),
    cmap=st.dictionaries(texts, entries, max_size=4),
    notes=st.tuples(texts, texts, texts),
    kind=st.sampled_from(REPAIRABLE + FAILING),
    u=st.floats(0, 0.999),
)
def test_every_malformation_is_read_as_planted(state, cmap, notes, kind, u) -> None:
    body = {"observation": notes[0], "dedup_check": notes[1], "cognitive_map": cmap,
            "action": "Turn(Right)", "reasoning": notes[2]}  # fmt: skip
    text = malform(render(state, body), kind, u)
    reply = parse_reply(text)
    if kind in FAILING:
        assert reply.error is not None
    else:
        assert reply.error is None and reply.repairs == (kind,)
        assert [e.label for e in reply.cognitive_map] == [k.strip() for k in cmap]
    assert read_state(text) == state


def test_a_reply_without_state_is_a_protocol_error() -> None:
    with pytest.raises(ProtocolError, match="no mimic state"):
        read_state('{"action": "Turn(Left)"}')


@pytest.mark.parametrize("style", NUMBERING)
def test_labels_are_numbered_in_the_episode_style(style: str) -> None:
    taken = {"office chair"}
    label = label_for("Chair", taken, style=style, u_phrase=0.0, u_qualifier=0.9)
    assert label == style.format("office chair", 2)
    assert label_for("Chair", taken | {label}, style=style, u_phrase=0.0, u_qualifier=0.9) == (
        style.format("office chair", 3)
    )
    assert label_for("Chair", taken, style=style, u_phrase=0.0, u_qualifier=0.0) == (
        "office chair near the window"
    )


@pytest.mark.parametrize("object_type", sorted(PHRASES))
def test_every_phrase_names_its_type_in_the_metrics_vocabulary(object_type: str) -> None:
    present = set(PHRASES)
    labels = [
        label_for(object_type, taken, style=style, u_phrase=u, u_qualifier=q)
        for style in NUMBERING
        for taken in ((), PHRASES[object_type])
        for u in np.linspace(0, 0.99, 8)
        for q in np.linspace(0, 0.99, 12)
    ]
    assert {canonical_type(label, present=present) for label in labels} == {object_type}
    assert canonical_type(type_word(object_type), present=present) == object_type


WORLD_TYPES = {kind.object_type for kind in KINDS.values()}


def test_every_type_the_world_holds_has_phrases() -> None:
    assert set(PHRASES) == WORLD_TYPES


@pytest.mark.parametrize("phrase", HALLUCINATIONS)
def test_hallucinations_name_no_type_the_world_holds(phrase: str) -> None:
    for label in (phrase, label_for(phrase, {phrase}, style="{0} ({1})", u_phrase=0.0,
                                    u_qualifier=1.0)):  # fmt: skip
        assert canonical_type(label, present=WORLD_TYPES) is None


def _episode(model: str, spawn: str = "office", k: int = 0, layouts: str = "paper") -> Trajectory:
    return run_episode(EpisodeSpec(model, "baseline", spawn, k, modality="both", layouts=layouts))


@pytest.fixture(scope="module")
def scout() -> Trajectory:
    return _episode("scout")


@pytest.fixture(scope="module")
def clean() -> Trajectory:
    return _episode(CLEAN)


def _positions(traj: Trajectory) -> list[tuple[float, float]]:
    return sorted((e.x, e.z) for e in traj.final_map)


def test_the_clean_mimic_walks_and_maps_like_the_scout(scout: Trajectory, clean) -> None:
    assert [s.action for s in clean.steps] == [s.action for s in scout.steps]
    assert _positions(clean) == _positions(scout)
    assert {e.label for e in clean.final_map}.isdisjoint({e.label for e in scout.final_map})


def test_its_own_frame_is_one_rigid_motion_of_the_spawn_frame(clean: Trajectory) -> None:
    own = _episode(CLEAN.replace("-spawn", ""))
    assert [s.action for s in own.steps] == [s.action for s in clean.steps]
    spawn = {e.label: (e.x, e.z) for e in clean.final_map}
    pairs = [(spawn[e.label], (e.x, e.z)) for e in own.final_map]
    assert len(pairs) == len(spawn) >= 10
    p, q = np.array([a for a, _ in pairs]), np.array([b for _, b in pairs])
    rot, shift = rigid_fit(p, q)
    assert np.abs(p @ rot.T + shift - q).max() <= 0.01  # both written to 0.01 m
    assert math.dist(shift, (0.0, 0.0)) > 0.1 or abs(rot[0, 1]) > 0.1


def test_wasted_steps_do_not_change_its_decisions(clean: Trajectory) -> None:
    noisy = _episode("mimic-spawn-s0-p0-h0-q0.3-r0-a0.2-b0")
    kept = [
        s.action
        for s in noisy.steps
        if s.parse_error is None and not PLANTED_INVALID.match(s.action)
    ]
    assert len(kept) < len(noisy.steps)
    if len(noisy.steps) == noisy.spec.max_steps:  # the budget ran out: its Term is forced
        kept = kept[:-1]
    assert kept == [s.action for s in clean.steps][: len(kept)]


def test_duplicates_come_on_re_entry_and_grow_with_p() -> None:
    def dups(model: str) -> set[tuple[str, int]]:
        # the scout never re-enters a room of the paper's office; this generated one it does
        state = read_state(_episode(model, "entrance", 2, "generated").steps[-1].raw_reply)
        ids = [r["id"] for r in state["map"].values() if "id" in r]
        return {(r["id"], r["visit"]) for r in state["map"].values()
                if "id" in r and ids.count(r["id"]) > 1 and "x" not in r}  # fmt: skip

    low, high = dups("mimic-p0.3-q0-a0"), dups("mimic-p1-q0-a0")
    assert {i for i, _ in low} <= {i for i, _ in high} and len(low) < len(high)
    assert all(visit >= 2 for _, visit in high)


@pytest.mark.parametrize("spawn", ["office", "kitchen", "entrance"])
def test_walking_back_re_enters_the_room_it_names(spawn: str) -> None:
    home, plain = _episode(CLEAN.replace("-b0", "-b1"), spawn), _episode(CLEAN, spawn)
    rooms = [s.room for s in home.steps]
    runs = [r for i, r in enumerate(rooms) if i == 0 or rooms[i - 1] != r]
    assert home.chosen_room == plain.chosen_room == rooms[-1]
    if plain.final_room == plain.chosen_room:  # already there: nothing to walk back to
        assert [s.action for s in home.steps] == [s.action for s in plain.steps]
    else:  # until every room is identified it walks like the mimic without the knob
        assert runs.count(rooms[-1]) == 2
        walk = [s.action for s in plain.steps][:-1]
        assert [s.action for s in home.steps][: len(walk)] == walk


def test_the_same_request_gets_the_same_reply() -> None:
    first, second = _episode("mimic", "kitchen", 1), _episode("mimic", "kitchen", 1)
    assert [s.raw_reply for s in first.steps] == [s.raw_reply for s in second.steps]
