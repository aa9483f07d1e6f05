"""Reply parsing: worked examples of what real models write, and fuzzing (never raises)."""

from __future__ import annotations

import json

import pytest
from hypothesis import given
from hypothesis import strategies as st

from pytest_emrd.agent import REPAIRS, Reply, parse_reply
from pytest_emrd.trajectory import MapEntry

GOOD = {
    "observation": "a desk",
    "dedup_check": "Desk_1 is new",
    "cognitive_map": {
        "Desk_1": {"type": "Desk", "room": "Office", "x": 1.5, "z": -2, "facing": "+z"}
    },
    "action": "Goto(Desk_1)",
}
DESK = MapEntry("Desk_1", "Desk", 1.5, -2.0, "Office", "+z")


BODY = json.dumps(GOOD, indent=2)


@pytest.mark.parametrize(
    ("text", "repairs"),
    [
        pytest.param(json.dumps(GOOD), (), id="plain"),
        pytest.param(f"```json\n{BODY}\n```", ("fence",), id="fenced"),
        pytest.param(f"Let me think. I see a desk.\n{json.dumps(GOOD)}\nThat is my answer.",
                     ("prose",), id="prose-around"),
        pytest.param(f"Here is my update:\n```json\n{BODY}\n```\nNext I go to the desk.",
                     ("fence", "prose"), id="prose-around-a-fence"),
        pytest.param("{'observation': 'a desk', 'dedup_check': 'Desk_1 is new', 'cognitive_map': "
                     "{'Desk_1': {'type': 'Desk', 'room': 'Office', 'x': 1.5, 'z': -2, 'facing': "
                     "'+z'},}, 'action': 'Goto(Desk_1)',}",
                     ("trailing_comma", "python_literal"), id="single-quotes"),
        pytest.param(json.dumps(GOOD).replace("1.5", '"1.5"').replace("-2", '"-2"'), (),
                     id="numbers-as-strings"),
        pytest.param(json.dumps(GOOD).replace("}}", "},}").replace('"Goto(Desk_1)"}',
                     '"Goto(Desk_1)",}'), ("trailing_comma",), id="trailing-commas"),
        pytest.param(BODY.replace('"x": 1.5,', '"x": 1.5,  // metres, my estimate\n')
                     .replace('"+z"\n', '"+z"  /* it\'s facing the window */\n'),
                     ("comment",), id="comments-with-an-apostrophe"),
        pytest.param("```json\n" + BODY.replace('"+z"', '"+z", // see http://x') + "\n```",
                     ("fence", "comment", "trailing_comma"), id="fenced-comment-and-comma"),
        pytest.param(json.dumps(GOOD).replace("is new", "is new // not a comment"), (),
                     id="slashes-inside-a-string"),
        pytest.param(f'```\n{{"draft": true}}\n```\n```json\n{json.dumps(GOOD)}\n```',
                     ("fence", "prose"), id="two-blocks-last-with-action"),
    ],
)  # fmt: skip
def test_tolerated_forms_are_read_and_their_repairs_named(text: str, repairs: tuple) -> None:
    reply = parse_reply(text)
    assert reply.error is None
    assert reply.action == "Goto(Desk_1)"
    assert reply.cognitive_map == (DESK,)
    assert reply.repairs == repairs


def test_missing_optional_keys_and_python_spellings() -> None:
    reply = parse_reply(
        "{'action': 'Term(Kitchen)', 'cognitive_map': {'Fridge_1': {'x': 2, 'z': 3, 'room': None}},"
        " 'reasoning': 'no hazards', 'flag': True}"
    )
    assert reply == Reply(
        cognitive_map=(MapEntry("Fridge_1", "", 2.0, 3.0, None, None),),
        action="Term(Kitchen)",
        reasoning="no hazards",
        repairs=("python_literal",),
    )


def test_map_as_a_list_of_labelled_objects() -> None:
    reply = parse_reply(
        '{"action": "Turn(Left)", "cognitive_map": [{"label": "Desk_1", "type": "Desk", "x": 1.5, '
        '"z": -2, "room": "Office", "facing": "+z"}, {"id": "Sofa", "x": 0, "z": 0}]}'
    )
    assert reply.cognitive_map == (DESK, MapEntry("Sofa", "", 0.0, 0.0))


def _with_desk(fields: str) -> str:
    """A reply whose map holds a desk written as ``fields`` (JSON), then a chair as asked."""
    return (
        '{"action": "Turn(Left)", "cognitive_map": {"Desk_1": ' + fields + ', "Chair_1": '
        '{"type": "Chair", "x": 0.5, "z": 1}}}'
    )


CHAIR = MapEntry("Chair_1", "Chair", 0.5, 1.0)


@pytest.mark.parametrize(
    ("fields", "x", "z", "repairs"),
    [
        ('{"type": "Desk", "x": "1.5", "z": "-2"}', 1.5, -2.0, ()),
        ('{"type": "Desk", "position": [1.5, -2]}', 1.5, -2.0, ("position_list",)),
        ('{"type": "Desk", "pos": [1.5, -2.0]}', 1.5, -2.0, ("position_list",)),
        ('{"type": "Desk", "coordinates": ["1.5", "-2"]}', 1.5, -2.0, ("position_list",)),
        ("[1.5, -2]", 1.5, -2.0, ("position_list",)),
        ('{"type": "Desk", "x": "2 metres", "z": "-2 m"}', 2.0, -2.0, ("unit",)),
        ('{"type": "Desk", "x": "2.5 m", "z": "-2.0m"}', 2.5, -2.0, ("unit",)),
        ('{"type": "Desk", "x": "250 cm", "z": "-2 Meters"}', 2.5, -2.0, ("unit",)),
        ('{"type": "Desk", "x": "2,5", "z": -2}', 2.5, -2.0, ("decimal_comma",)),
        ('{"type": "Desk", "x": "-0,75", "z": "1,5 m"}', -0.75, 1.5, ("unit", "decimal_comma")),
        ('{"type": "Desk", "xz": ["2,5 m", -2]}', 2.5, -2.0,
         ("position_list", "unit", "decimal_comma")),
    ],
    ids=["string-numbers", "position-list", "pos-list", "coordinates-strings", "bare-list",
         "metres", "m", "cm", "decimal-comma", "comma-and-unit", "all-three"],
)  # fmt: skip
def test_positions_in_other_notations_are_read_and_their_repairs_named(
    fields: str, x: float, z: float, repairs: tuple[str, ...]
) -> None:
    reply = parse_reply(_with_desk(fields))
    assert reply.error is None
    desk, chair = reply.cognitive_map
    assert (desk.label, desk.x, desk.z) == ("Desk_1", pytest.approx(x), pytest.approx(z))
    assert chair == CHAIR
    assert reply.repairs == repairs


def test_position_repairs_join_the_syntax_repairs_in_order() -> None:
    body = _with_desk('{"x": "2,5", "z": 1}')
    reply = parse_reply(f"```json\n{body}\n```")
    assert reply.error is None and reply.repairs == ("fence", "decimal_comma")


@pytest.mark.parametrize(
    ("fields", "reason"),
    [
        ('{"type": "Desk", "x": "near the door", "z": 1}', 'as x: "near the door"'),
        ('{"type": "Desk", "x": null, "z": 1}', "as x: null"),
        ('{"type": "Desk", "x": 1, "z": "far"}', 'as z: "far"'),
        ('{"type": "Desk", "x": true, "z": 1}', "as x: true"),
        ('{"type": "Desk", "x": NaN, "z": 1}', "as x: NaN"),
        ('{"type": "Desk", "x": "6 ft", "z": 1}', 'as x: "6 ft"'),
        ('{"type": "Desk", "x": "1,5,2", "z": 1}', 'as x: "1,5,2"'),
        ('{"type": "Desk", "x": 1}', "as z: null"),
        ('{"type": "Desk", "room": "Office"}', "has no x and z"),
        ('{"type": "Desk", "position": [1.5, 0.8, -2]}', "has no x and z"),
        ('{"type": "Desk", "position": "near the door"}', "has no x and z"),
        ('"near the door"', "has no x and z"),
        ("[1.5]", "has no x and z"),
    ],
    ids=["words", "null", "words-in-z", "bool", "nan", "feet", "two-commas", "no-z", "no-xz",
         "xyz-list", "position-words", "entry-is-words", "one-number-list"],
)  # fmt: skip
def test_an_unreadable_position_is_a_parse_failure_naming_the_entry(
    fields: str, reason: str
) -> None:
    reply = parse_reply(_with_desk(fields))
    assert reply.error is not None
    assert reply.error.startswith("cognitive_map entry 'Desk_1' ") and reason in reply.error
    assert reply.cognitive_map == ()
    assert reply.action == "Turn(Left)"


def test_an_unquoted_decimal_comma_is_a_parse_failure() -> None:
    """``"x": 2,5`` is not JSON; no repair guesses where the number ends."""
    reply = parse_reply(_with_desk('{"type": "Desk", "x": 2,5, "z": 1}'))
    assert reply.error is not None and "no JSON object" in reply.error


@given(
    st.floats(-50, 50, allow_nan=False).map(lambda v: round(v, 3)),
    st.sampled_from(["{}", "{} m", "{}m", "{} metres", "{} meters"]),
    st.booleans(),
)
def test_a_written_coordinate_reads_as_the_number(value: float, unit: str, comma: bool) -> None:
    written = unit.format(repr(value))
    if comma:
        written = written.replace(".", ",")
    reply = parse_reply(_with_desk(json.dumps({"x": written, "z": 0})))
    assert reply.error is None
    assert reply.cognitive_map[0].x == pytest.approx(value, abs=1e-12)
    expected = {"unit"} if unit != "{}" else set()
    if comma and "." in repr(value):
        expected.add("decimal_comma")
    assert set(reply.repairs) == expected


@pytest.mark.parametrize(
    ("text", "reason"),
    [
        ("", "empty reply"),
        ("I will turn left.", "no JSON object"),
        ('{"observation": "x", "cognitive_map": {}}', "no action"),
        ('{"action": "Turn(Left)"}', "no cognitive_map"),
        ('{"action": "Turn(Left)", "cognitive_map": "Desk at 1,2"}', "is str, not an object"),
        ('{"action": "Turn(Left)", "cognitive_map": [1, 2]}', "items are not objects"),
        ('{"action": "Turn(Left)", "cognitive_map": [{"x": 1, "z": 2}]}', "without label"),
        ('{"action": "Turn(Left), "cognitive_map": {}', "no JSON object"),
        ("x" * 300_000, "exceeds"),
        (BODY[: BODY.index('"room"')], "no JSON object"),
        (BODY.replace('"Office",', '"Office"'), "no JSON object"),
        (
            BODY.replace('"action"', "action").replace('"observation"', "observation"),
            "no JSON object",
        ),
        (BODY.replace('"+z"\n    }', '"+z"\n    },\n    ...'), "no JSON object"),
    ],
    ids=[
        "empty",
        "prose-only",
        "no-action",
        "no-map",
        "map-is-text",
        "map-list-of-numbers",
        "map-list-unlabelled",
        "broken-json",
        "runaway",
        "truncated-at-the-token-limit",
        "missing-comma",
        "unquoted-keys",
        "ellipsis-for-elided-entries",
    ],
)
def test_unreadable_replies_say_why(text: str, reason: str) -> None:
    reply = parse_reply(text)
    assert reply.error is not None and reason in reply.error
    assert reply.cognitive_map == ()


def test_action_survives_an_unreadable_map() -> None:
    reply = parse_reply('{"action": "Turn(Left)", "cognitive_map": 7}')
    assert reply.action == "Turn(Left)" and reply.error is not None


json_values = st.recursive(
    st.none() | st.booleans() | st.floats(allow_nan=True) | st.integers() | st.text(max_size=8),
    lambda inner: (
        st.lists(inner, max_size=4) | st.dictionaries(st.text(max_size=6), inner, max_size=4)
    ),
    max_leaves=20,
)


@given(st.text(max_size=300))
def test_never_raises_on_arbitrary_text(text: str) -> None:
    reply = parse_reply(text)
    assert isinstance(reply, Reply) and set(reply.repairs) <= set(REPAIRS)


@given(
    st.dictionaries(
        st.sampled_from(["action", "cognitive_map", "reasoning", "x", "z"]), json_values, max_size=5
    )
)
def test_never_raises_on_arbitrary_json_objects(obj: dict) -> None:
    reply = parse_reply(json.dumps(obj))
    assert reply.error is not None or reply.action


@given(st.text(alphabet="{}[]'\",:0123456789.-eE tnrufalsTFN\\\n`", max_size=120))
def test_never_raises_on_json_like_noise(text: str) -> None:
    assert isinstance(parse_reply(text), Reply)


@given(
    st.dictionaries(
        st.text(min_size=1, max_size=10).filter(str.strip),
        st.fixed_dictionaries(
            {"type": st.text(max_size=8), "x": st.floats(-50, 50), "z": st.floats(-50, 50)}
        ),
        max_size=6,
    ),
    st.sampled_from(["plain", "fenced", "prose"]),
)
def test_well_formed_maps_round_trip(cmap: dict, wrapping: str) -> None:
    body = json.dumps({"action": "Turn(Right)", "cognitive_map": cmap})
    text = {"plain": body, "fenced": f"```json\n{body}\n```", "prose": f"Map:\n{body}\nDone."}[
        wrapping
    ]
    reply = parse_reply(text)
    assert reply.error is None
    assert [(e.label, e.x, e.z) for e in reply.cognitive_map] == [
        (k.strip(), v["x"], v["z"]) for k, v in cmap.items()
    ]


def test_a_repeated_entry_reads_alike_and_a_zero_keeps_its_sign() -> None:
    assert parse_reply(json.dumps(GOOD)).cognitive_map == (DESK,)
    assert parse_reply(json.dumps(GOOD)).cognitive_map == (DESK,)
    for x in (0.0, -0.0, 0.0):
        cmap = {"Desk_1": {"type": "Desk", "x": x, "z": 1.5}}
        (entry,) = parse_reply(json.dumps({"action": "Stop", "cognitive_map": cmap})).cognitive_map
        assert str(entry.x) == str(x)


_JSON_VALUES = st.recursive(
    st.none() | st.booleans() | st.floats(allow_nan=False) | st.text(max_size=8),
    lambda inner: st.lists(inner, max_size=3) | st.dictionaries(st.text(max_size=6), inner),
    max_leaves=12,
)
_PIECES = st.lists(
    st.one_of(
        st.dictionaries(st.text(max_size=6), _JSON_VALUES, max_size=4).map(json.dumps),
        st.sampled_from(["{", "}", "```json\n", "\n```", "'", '"', "// c\n", "/* c */", ",}"]),
        st.text(max_size=12),
    ),
    max_size=6,
)


@given(_PIECES.map("".join))
def test_valid_json_spans_are_found_as_the_token_scan_finds_them(text: str) -> None:
    """The span of an object that is valid JSON is taken from the JSON decoder; it must be the
    span the brace-and-string token scan finds, on any mix of JSON, prose, fences, stray
    quotes, braces and comments (the scan alone is the oracle)."""
    from pytest_emrd.agent import _parse

    fast = _parse._balanced_objects(text)
    decode = _parse._json_end
    try:
        _parse._json_end = lambda text, start: None  # type: ignore[assignment]
        scanned = _parse._balanced_objects(text)
    finally:
        _parse._json_end = decode
    assert fast == scanned
