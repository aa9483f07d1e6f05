"""Vocabulary of the matcher: what models write -> AI2-THOR engine types.

:func:`canonical_type` reads a label the way English reads a noun phrase: the **head noun**
says what the thing is, the words before it only which one or what kind. In order: (1) split
words (CamelCase, ids, asides, instance numbers and letters dropped); (2) cut the phrase
before a :data:`QUALIFIER_WORDS` word (past :data:`POSITION_WORDS` when the words before them
name no type), dropping trailing :data:`STATE_WORDS`; (3) the longest run of at most four
words *ending at the last word* that is a key of :data:`SYNONYMS` or an engine type name
(last word as written, then singular) denotes its types, except a :data:`PART_WORDS` head
after an object (``fridge door``); (4) else the last word is corrected to the key at the
least rapidfuzz OSA distance (similarity >= :data:`FUZZY_THRESHOLD`, at least
:data:`FUZZY_MIN_LENGTH` letters, one best answer, never a word of :data:`REAL_WORDS`).
The rules, their examples and their measured effect are on the docs page "Reading what a
model writes" (``docs/interpretation/vocabulary.md``).

Inside an episode (:class:`TypeResolver`) the first candidate the layout holds wins. Text that
denotes no engine type, or only types the layout lacks, is *unrecognised*
(:attr:`Matching.unrecognised`): a hallucination, which (as Eq. AEC's ``min`` intends) counts
for nothing in AEC, PA, TBS, SIR or the spells, but does count in Miller's load ``|M_{t-1}|``,
which the paper defines on the map's labels.
"""

from __future__ import annotations

import json
import re
from collections.abc import Iterable
from fractions import Fraction
from functools import lru_cache
from importlib import resources
from typing import Final

from rapidfuzz import process
from rapidfuzz.distance import OSA

#: The vocabulary as data (``vocab.json`` beside this module): engine types, synonyms, and the
#: word lists of steps 2 and 4.
_DATA: Final = json.loads(resources.files(__package__).joinpath("vocab.json").read_text("utf-8"))

#: AI2-THOR ``objectType`` names (iTHOR + ProcTHOR, incl. ``Doorway``), the matcher's types.
ENGINE_TYPES: Final[frozenset[str]] = frozenset(_DATA["engine_types"])
#: Word VLMs use -> the engine types it names, most likely first. ``vocab.json`` lists per
#: engine types (most likely first) the words VLMs use for them (joined, singular, lower case);
#: a word lists only types it is a name for, never a look-alike: a type the layout lacks is a
#: hallucination, not a licence to pick the nearest thing it has. Engine type names need no
#: entry (``diningtable`` denotes ``DiningTable``).
SYNONYMS: Final[dict[str, tuple[str, ...]]] = {
    word: tuple(types.split())
    for types, words in _DATA["synonyms"].items()
    for word in words.split()
}
#: Words that open a qualifier phrase; the label is cut before the first of them.
QUALIFIER_WORDS: Final[frozenset[str]] = frozenset(_DATA["qualifier_words"])
#: Qualifier words that are also adjectives of position (``back left chair``).
POSITION_WORDS: Final = frozenset({"left", "right"})
#: States written after the noun (``door open``), dropped from the end of the phrase.
STATE_WORDS: Final[frozenset[str]] = frozenset(_DATA["state_words"])
#: Head nouns that, after a modifier naming an object, name a part of it (``fridge door``).
PART_WORDS: Final = frozenset({"door", "seat"})
#: Misspelling correction: least rapidfuzz OSA normalised similarity to a key (1 - edits /
#: longer length; 0.8 is one edit in 5 to 9 letters, two in 10 to 14).
FUZZY_THRESHOLD: Final = 0.8
#: Misspelling correction: fewest letters of a word (and of a key) it applies to.
FUZZY_MIN_LENGTH: Final = 5

#: English words within :data:`FUZZY_THRESHOLD` of a key that are no spelling of it (from
#: pyspellchecker's English frequency list, every word of at least 5 letters that step 4
#: would otherwise correct, less misspellings and words naming the same thing). Never
#: corrected: ``cable`` is a cable, not a misspelt table.
REAL_WORDS: Final[frozenset[str]] = frozenset(_DATA["real_words"])

_CAMEL = re.compile(r"(?<=[a-z0-9])(?=[A-Z])|(?<=[A-Z])(?=[A-Z][a-z]{2})")
_ASIDE = re.compile(r"\(.*?\)|\[.*?\]|\{.*?\}")
_WORDS = re.compile(r"[a-z]+|[0-9]+")
#: Every key of steps 3 and 4 -> the types it denotes: engine type names, then SYNONYMS.
_KEYS: Final = {**{t.lower(): (t,) for t in ENGINE_TYPES}, **SYNONYMS}
_MAX_RUN: Final = 4
_EDITS_PER_LETTER: Final = Fraction(1) - Fraction(str(FUZZY_THRESHOLD))
_FUZZY_KEYS: Final = tuple(sorted(k for k in _KEYS if len(k) >= FUZZY_MIN_LENGTH))
#: Plural endings -> their singular, and the fewest letters a word needs for each.
_PLURALS: Final = (("ives", "ife", 5), ("ves", "f", 4), ("es", "", 4), ("s", "", 3))


def _singulars(word: str) -> tuple[str, ...]:
    """``word`` then its plausible singulars (``shelves`` -> ``shelf``, ``knives`` ->
    ``knife``, ``couches`` -> ``couch``)."""
    return word, *(
        word.removesuffix(end) + singular
        for end, singular, least in _PLURALS
        if len(word) >= least and word.endswith(end) and not word.endswith("ss")  # glass
    )


def _lookup(key: str) -> tuple[str, ...]:
    return _KEYS.get(key, ())


def head_words(text: str) -> tuple[str, ...]:
    """Step 1's words: split, lower-cased, instance numbers and letters dropped."""
    spaced = _CAMEL.sub(" ", _ASIDE.sub(" ", text))
    words = _WORDS.findall(spaced.lower())
    return tuple(w for w in words if not w.isdigit() and len(w) > 1)


def noun_phrase(words: tuple[str, ...]) -> tuple[str, ...]:
    """Step 2: ``words`` up to the first qualifier word (not counting the first word), read
    past ``left``/``right`` when the words before them name no type; trailing states dropped."""
    for i, word in enumerate(words[1:], 1):
        if word in QUALIFIER_WORDS and (
            word not in POSITION_WORDS or _denotes(_trimmed(words[:i]))  # "back left chair"
        ):
            return _trimmed(words[:i])
    return _trimmed(words)


def _trimmed(words: tuple[str, ...]) -> tuple[str, ...]:
    end = len(words)
    while end > 1 and words[end - 1] in STATE_WORDS:
        end -= 1
    return words[:end]


def _exact(words: tuple[str, ...]) -> tuple[str, ...]:
    """Step 3: candidates of the longest run ending at the head noun that is a key (longest
    first, each with the last word as written and then made singular)."""
    for size in range(min(_MAX_RUN, len(words)), 0, -1):
        run = words[-size:]
        for last in _singulars(run[-1]):
            hit = _lookup("".join(run[:-1]) + last)
            if hit:
                return () if size == 1 and _is_part(words) else hit
    return ()


def _is_part(words: tuple[str, ...]) -> bool:
    """``fridge door``: a part word after a word that names an object (step 3)."""
    if len(words) < 2 or not any(f in PART_WORDS for f in _singulars(words[-1])):
        return False
    return any(_lookup(f) for f in _singulars(words[-2]))


def _fuzzy(words: tuple[str, ...]) -> tuple[str, ...]:
    """Step 4: candidates of the key closest to the head noun (as written, then singular)."""
    forms = _singulars(words[-1])
    if any(f in REAL_WORDS for f in forms):
        return ()
    for form in forms:
        if len(form) < FUZZY_MIN_LENGTH:
            continue
        # 1 - edits / longer >= FUZZY_THRESHOLD, in whole numbers (no rounding at the edge)
        near = [
            (edits, key)
            for key, edits, _ in process.extract(
                form, _FUZZY_KEYS, scorer=OSA.distance, score_cutoff=len(form), limit=None
            )
            if edits <= _EDITS_PER_LETTER * max(len(form), len(key))
        ]
        if near:
            least = min(edits for edits, _ in near)
            best = {_lookup(key) for edits, key in near if edits == least}
            return best.pop() if len(best) == 1 else ()
    return ()


@lru_cache(maxsize=8192)
def candidate_types(text: str) -> tuple[str, ...]:
    """Engine types ``text`` may denote, most likely first; ``()`` for none (a hallucination).

    See the module docstring for the procedure. ``candidate_types("table by the door")`` is
    ``("DiningTable", "CoffeeTable", "SideTable", "Desk")``; ``candidate_types("ghost")`` and
    ``candidate_types("exit sign")`` are ``()``; ``candidate_types("chiar")`` is
    ``("Chair",)``.

    :param text: A label or type name as the model wrote it.
    :returns: Engine types, most likely first; ``()`` for none.
    """
    return _denotes(noun_phrase(head_words(text)))


def _denotes(phrase: tuple[str, ...]) -> tuple[str, ...]:
    """Candidates of a noun phrase (steps 3 and 4); ``()`` for an empty phrase."""
    return (_exact(phrase) or _fuzzy(phrase)) if phrase else ()


def canonical_type(text: str, *, present: Iterable[str] | None = None) -> str | None:
    """The AI2-THOR ``objectType`` a label or type name written by a model denotes.

    ``canonical_type("office chair") == "Chair"``, ``"TV" -> "Television"``,
    ``"chairs (2)" -> "Chair"``, ``"small wooden table by the door" -> "DiningTable"``,
    ``"the red armchair" -> "ArmChair"``, ``"table lamp" -> "DeskLamp"``,
    ``"fire extinguisher" -> None``, ``"exit sign" -> None``.

    ``present``: the types a layout holds. Given, the first candidate among them wins
    (``canonical_type("table", present={"Desk"}) == "Desk"``) and None is returned when the
    layout holds none of the candidates (``canonical_type("sofa", present={"ArmChair"})`` is
    None). Without it, the most likely engine type is returned. None means the text names no
    engine type (or none the layout holds): a hallucination.

    :param text: A label or type name as the model wrote it.
    :param present: The types the layout holds; None to take the most likely engine type.
    :returns: The ``objectType``, or None for a hallucination.
    """
    candidates = candidate_types(text)
    if present is None:
        return candidates[0] if candidates else None
    held = set(present)
    return next((c for c in candidates if c in held), None)


class TypeResolver:
    """Resolves written type names to the index of a ground-truth type of one episode.

    An entry's ``object_type`` is read first, then its label; each by
    :func:`canonical_type` restricted to the episode's types, so a type the layout does not
    hold resolves to nothing (-1), never to a neighbouring type it holds.
    """

    def __init__(self, types: Iterable[str]) -> None:
        self.names: list[str] = sorted(set(types))
        """Ground-truth types, sorted; a type's index is its position here."""
        self.index: dict[str, int] = {t: i for i, t in enumerate(self.names)}
        self._lower = {t.lower(): t for t in self.names}
        self._known: dict[tuple[str, str], int] = {}  # (object_type, label) -> index

    def resolve(self, object_type: str, label: str) -> int:
        """Type index of an entry (its ``object_type`` first, then its label); -1 if none."""
        hit = self._known.get((object_type, label))
        if hit is None:
            hit = self._resolve_text(object_type)
            if hit < 0:
                hit = self._resolve_text(label)
            self._known[(object_type, label)] = hit
        return hit

    def _resolve_text(self, text: str) -> int:
        if text in self.index:
            return self.index[text]
        found = canonical_type(text, present=self.index)
        if found is None:  # a layout type outside the engine vocabulary, written as named
            found = self._lower.get("".join(head_words(text)))
        return -1 if found is None else self.index[found]
