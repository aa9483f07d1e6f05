"""Shipped texts: edit scripts rebuild any string exactly, and the system prompt is named."""

from __future__ import annotations

import json

import pytest
from hypothesis import given
from hypothesis import strategies as st

from pytest_emrd.agent._prompt import build_system_prompt
from pytest_emrd.cassette._shared import (
    SHARED_FILE,
    NewerTextError,
    apply_edit,
    edit_script,
    pack,
    shared_texts,
    text_id,
    unpack,
)
from pytest_emrd.trajectory import MODALITIES, VARIANTS
from pytest_emrd.world._episode import paper_office
from pytest_emrd.world._layout import generate_layout

_words = st.lists(st.sampled_from(["map", "desk", " ", ",", "é", "\n", "{", "Chair_12", "0.25"]))


def test_worked_example_of_an_edit_script():
    base = "The quick brown fox jumps over the lazy dog near the river bank."
    text = "The quick brown fox leaps over the lazy dog near the river bank!"
    script = edit_script(text, base)
    assert script == [0, 20, "leaps", 25, 38, "!"]
    assert apply_edit(base, script) == text


@given(st.text(max_size=300), st.text(max_size=300))
def test_any_text_is_rebuilt_exactly_from_any_base(text, base):
    assert apply_edit(base, edit_script(text, base)) == text


@given(_words, _words, _words)
def test_texts_sharing_passages_round_trip_and_copy_what_they_share(head, middle, tail):
    shared = "".join(middle) + " a passage long enough to be copied rather than repeated"
    base, text = "".join(head) + shared, shared + "".join(tail)
    script = edit_script(text, base)
    assert apply_edit(base, script) == text
    assert any(isinstance(op, int) for op in script)  # the shared passage is a copy
    assert edit_script(text, base) == script  # deterministic


@pytest.mark.parametrize(
    "script",
    [[0], [0, 5, 3], [-1, 2], [0, 99], [True, 1], ["x", 1.5, 2]],
    ids=["lone-int", "odd-ints", "negative", "past-the-end", "bool", "float"],
)
def test_a_broken_script_is_a_value_error(script):
    with pytest.raises(ValueError, match="edit script"):
        apply_edit("short base", script)


def test_the_shipped_file_names_each_text_by_its_hash():
    texts = json.loads(SHARED_FILE.read_text(encoding="utf-8"))
    assert texts and all(name == text_id(text) for name, text in texts.items())


@pytest.mark.parametrize("variant", VARIANTS)
@pytest.mark.parametrize("modality", MODALITIES)
def test_every_paper_prompt_is_named_for_a_few_hundred_bytes(variant, modality):
    prompt = build_system_prompt(paper_office().inventory(), variant, modality=modality)
    entry = pack(prompt)
    assert isinstance(entry, dict) and unpack(entry) == prompt
    assert len(json.dumps(entry)) < len(prompt) / 5


def test_a_generated_layout_prompt_is_an_edit_of_the_shipped_one():
    prompt = build_system_prompt(generate_layout(3).inventory(), "default", modality="both")
    entry = pack(prompt)
    assert isinstance(entry, dict) and entry["from"] in shared_texts()
    assert unpack(entry) == prompt


@given(st.text(max_size=2000))
def test_unrelated_strings_are_stored_as_they_are(text):
    assert pack(text) == text and unpack(text) == text


def test_naming_a_text_this_release_lacks_is_a_newer_text_error():
    with pytest.raises(NewerTextError, match="newer pytest-emrd"):
        unpack({"from": "0123456789abcdef", "edit": [0, 1]})
    with pytest.raises(ValueError, match="not a string or"):
        unpack({"from": "0123456789abcdef"})
