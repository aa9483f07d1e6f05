"""How the ``mimic`` agents word things: labels, types, hallucinations, wrappers, bad actions.

Tables of the phrasings real VLMs use in EMRD cognitive maps, per engine type of the office.
Every choice is a pure function of a uniform number in [0, 1) that the caller draws from the
request content (:func:`pick`), so the same episode always words the same object the same way.
Hallucinated objects (:data:`HALLUCINATIONS`) are things an office plausibly holds but the
EMRD office never does, worded so that no engine type is named anywhere in the text: they
must match nothing.
"""

from __future__ import annotations

from collections.abc import Container, Sequence
from typing import Final

#: Engine type -> what a VLM calls such an object in a label, most common first.
PHRASES: Final[dict[str, tuple[str, ...]]] = {
    "Chair": ("office chair", "chair", "desk chair", "swivel chair", "black chair"),
    "ArmChair": ("armchair", "lounge chair", "arm chair", "easy chair"),
    "Stool": ("stool", "bar stool", "kitchen stool"),
    "Desk": ("desk", "office desk", "work desk", "wooden desk"),
    "DiningTable": ("conference table", "meeting table", "long table", "table"),
    "ShelvingUnit": ("shelf", "bookshelf", "shelving unit", "bookcase"),
    "Television": ("TV", "television", "flat screen TV", "wall TV"),
    "Fridge": ("fridge", "refrigerator"),
    "CounterTop": ("kitchen counter", "counter", "countertop", "worktop"),
    "HousePlant": ("plant", "potted plant", "houseplant", "indoor plant"),
    "Laptop": ("laptop", "laptop computer", "notebook computer"),
    "Sink": ("sink", "kitchen sink"),
    "Microwave": ("microwave", "microwave oven"),
    "CoffeeMachine": ("coffee machine", "coffee maker", "espresso machine"),
    "Doorway": ("doorway", "open doorway", "passage", "door frame"),
    "Door": ("exit door", "main exit", "front door", "emergency exit"),
}
#: Engine type -> the short noun written in the entry's ``type`` field (default: the type in
#: lower case, ``Chair`` -> ``chair``).
TYPE_WORDS: Final[dict[str, str]] = {
    "DiningTable": "table",
    "ShelvingUnit": "shelf",
    "Television": "TV",
    "CounterTop": "counter",
    "HousePlant": "plant",
    "CoffeeMachine": "coffee machine",
    "Door": "exit door",
}
#: Locative qualifiers appended to some labels (probability :data:`QUALIFIED`).
QUALIFIERS: Final[tuple[str, ...]] = (
    "near the window",
    "by the door",
    "in the corner",
    "next to the table",
    "against the wall",
    "on the left",
)
QUALIFIED: Final = 0.2
#: How an episode numbers a repeated phrase (``{0}`` phrase, ``{1}`` number); one per episode.
NUMBERING: Final[tuple[str, ...]] = ("{0} ({1})", "{0} {1}", "{0} #{1}", "{0}_{1}")
#: Objects an office plausibly holds and the EMRD office never does (type field = label).
HALLUCINATIONS: Final[tuple[str, ...]] = (
    "fire extinguisher",
    "whiteboard",
    "water cooler",
    "printer",
    "coat rack",
    "projector",
    "wall clock",
    "first aid kit",
    "recycling bin",
    "umbrella stand",
)
#: Words around a reply's JSON when it comes with prose (before, after).
PROSE: Final[tuple[tuple[str, str], ...]] = (
    ("Here is my updated cognitive map and next action:", ""),
    ("Let me update my map with what I can see.", "I will keep exploring."),
    ("", "This keeps the map consistent with the previous step."),
    ("Observation processed. Output:", "Proceeding."),
)
#: Comments a reply puts after its action line when it comments its JSON.
COMMENTS: Final[tuple[str, ...]] = (
    "// continuing the sweep",
    "// next step of my plan",
    "/* positions are estimates */",
    "// it's the safest option for now",
)
#: Actions the world refuses (``{0}``: the label of an object in view, or ``the exit``).
INVALID_ACTIONS: Final = ("MoveAhead", "Goto(the {0})", "Turn(Back)", "Goto(nearest exit)")


def pick(options: Sequence[str], u: float) -> str:
    """The option a uniform number ``u`` in [0, 1) selects (equal odds)."""
    return options[min(int(u * len(options)), len(options) - 1)]


def label_for(
    object_type: str, taken: Container[str], *, style: str, u_phrase: float, u_qualifier: float
) -> str:
    """A free-form label for an object of ``object_type`` not in ``taken``: a phrase (an
    unknown type in lower case), a qualifier when ``u_qualifier < QUALIFIED``, and the lowest
    free number from 2 on in ``style`` (one of :data:`NUMBERING`) when the phrase is taken."""
    phrase = pick(PHRASES.get(object_type, (object_type.lower(),)), u_phrase)
    if u_qualifier < QUALIFIED:
        phrase = f"{phrase} {pick(QUALIFIERS, u_qualifier / QUALIFIED)}"
    label, n = phrase, 2
    while label in taken:
        label, n = style.format(phrase, n), n + 1
    return label


def type_word(object_type: str) -> str:
    """What the ``type`` field says for an object of ``object_type``."""
    return TYPE_WORDS.get(object_type, object_type.lower())
