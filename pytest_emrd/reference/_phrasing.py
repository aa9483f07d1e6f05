"""How the ``mimic`` agents word things: labels, types, hallucinations, wrappers, bad actions.

Tables of the phrasings real VLMs use in EMRD cognitive maps, per engine type of the office.
Every choice is a pure function of a uniform number in [0, 1) that the caller draws from the
request content (:func:`pick`), so the same episode always words the same object the same way.
Hallucinated objects (:data:`HALLUCINATIONS`) are things an office plausibly holds but the
EMRD office never does, worded so that no engine type is named anywhere in the text: they
must match nothing.
"""

from __future__ import annotations

import json
from collections.abc import Container, Sequence
from importlib import resources
from typing import Final

#: The tables as data (``phrasing.json`` beside this module).
_DATA: Final = json.loads(resources.files(__package__).joinpath("phrasing.json").read_text("utf-8"))

#: Engine type -> what a VLM calls such an object in a label, most common first.
PHRASES: Final[dict[str, list[str]]] = _DATA["phrases"]
#: Engine type -> the short noun written in the entry's ``type`` field (default: the type in
#: lower case, ``Chair`` -> ``chair``).
TYPE_WORDS: Final[dict[str, str]] = _DATA["type_words"]
#: Locative qualifiers appended to some labels (probability :data:`QUALIFIED`).
QUALIFIERS: Final[list[str]] = _DATA["qualifiers"]
QUALIFIED: Final = 0.2
#: How an episode numbers a repeated phrase (``{0}`` phrase, ``{1}`` number); one per episode.
NUMBERING: Final[list[str]] = _DATA["numbering"]
#: Objects an office plausibly holds and the EMRD office never does (type field = label).
HALLUCINATIONS: Final[list[str]] = _DATA["hallucinations"]
#: Words around a reply's JSON when it comes with prose (``[before, after]``).
PROSE: Final[list[list[str]]] = _DATA["prose"]
#: Comments a reply puts after its action line when it comments its JSON.
COMMENTS: Final[list[str]] = _DATA["comments"]
#: Actions the world refuses (``{0}``: the label of an object in view, or ``the exit``).
INVALID_ACTIONS: Final[list[str]] = _DATA["invalid_actions"]


def pick(options: Sequence[str], u: float) -> str:
    """The option a uniform number ``u`` in [0, 1) selects (equal odds)."""
    return options[min(int(u * len(options)), len(options) - 1)]


def label_for(
    object_type: str, taken: Container[str], *, style: str, u_phrase: float, u_qualifier: float
) -> str:
    """A free-form label for an object of ``object_type`` not in ``taken``: a phrase (an
    unknown type in lower case), a qualifier when ``u_qualifier < QUALIFIED``, and the lowest
    free number from 2 on in ``style`` (one of :data:`NUMBERING`) when the phrase is taken."""
    phrase = pick(PHRASES.get(object_type, [object_type.lower()]), u_phrase)
    if u_qualifier < QUALIFIED:
        phrase = f"{phrase} {pick(QUALIFIERS, u_qualifier / QUALIFIED)}"
    label, n = phrase, 2
    while label in taken:
        label, n = style.format(phrase, n), n + 1
    return label


def type_word(object_type: str) -> str:
    """What the ``type`` field says for an object of ``object_type``."""
    return TYPE_WORDS.get(object_type, object_type.lower())
