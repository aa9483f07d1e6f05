"""Vocabulary of the matcher: what models write -> AI2-THOR engine types.

A VLM names the objects of its cognitive map in its own words: ``"office chair"``,
``"TV"``, ``"chairs (2)"``, ``"Chair_3"``, ``"small wooden table by the door"``,
``"the red armchair"``. :func:`canonical_type` reads such a text and returns the AI2-THOR
``objectType`` it denotes, or None when it denotes none. The procedure, in order:

1. **Split words.** CamelCase and acronyms are split (``DiningTable`` -> ``dining table``,
   ``TVStand`` -> ``tv stand``), then the text is lower-cased; ``(...)``/``[...]``/``{...}``
   asides are removed (``chairs (2)`` -> ``chairs``); anything that is not a letter or a digit
   separates words (``Chair_3`` -> ``chair 3``, ``chair#2``, ``chair-2``).
2. **Cut qualifiers.** The text is cut at the first word that opens a locative or descriptive
   phrase (:data:`QUALIFIER_WORDS`: ``near``, ``by``, ``next``, ``beside``, ``in``, ``on``,
   ``at``, ``with``, ``of``, ...), so ``chair near the window`` is read as ``chair``, never as
   ``window``. Only when the words before the cut name no type is the whole text read
   (``back left chair``: ``left`` is a position, ``chair`` the head noun).
3. **Find the head noun.** Words that are numbers or single letters (instance suffixes,
   ``chair 2``, ``stool b``, ``2 chairs``) are dropped. Among the remaining words, the longest
   run of consecutive words that names a type is taken, the rightmost on equal length (English
   puts the head noun last: ``small wooden table`` -> ``table``, ``office chair`` ->
   ``office chair`` -> ``Chair``). A run names a type when its words joined (``arm chair`` ->
   ``armchair``), or joined with the last word made singular (``chairs``, ``shelves``,
   ``couches``, ``boxes``), is a key of :data:`SYNONYMS` or the lower-cased name of an engine
   type (:data:`ENGINE_TYPES`).
4. **Candidates.** A synonym lists the engine types it may denote, most likely first
   (``table`` -> ``DiningTable``, ``CoffeeTable``, ``SideTable``, ``Desk``); an engine type's
   own name denotes only itself.

Inside an episode (:class:`TypeResolver`) the first candidate the layout actually holds wins,
so ``table`` is the ``DiningTable`` where the layout has one and a ``Desk`` where it has no
table, and ``door`` is a ``Doorway`` where the layout has doorways.

**Hallucinations.** Text that denotes no engine type (``fire extinguisher``, ``ghost``), and
an engine type the layout does not hold (a ``sofa`` in an office without one), match no
ground-truth object: the entry is *unrecognised* (:attr:`Matching.unrecognised`). As in the
paper's Eq. AEC, whose ``min(|M_k|, |E_k|)`` term "prevents hallucinated or double-counted
objects from inflating the score", such entries count for nothing: not in ``K`` (AEC, PA),
not in ``M_t`` of TBS, not in SIR's ``M_first``/``M_return``, and they open no forgetting
spell. They do count in Miller's load ``|M_{t-1}|``, which the paper defines on the map's
labels (what the model holds), not on matched objects.
"""

from __future__ import annotations

import re
from collections.abc import Iterable
from functools import lru_cache
from typing import Final


def _split(text: str) -> list[str]:
    return text.split()


#: AI2-THOR ``objectType`` names (iTHOR + ProcTHOR, incl. ``Doorway``), the matcher's types.
ENGINE_TYPES: Final[frozenset[str]] = frozenset(
    _split(
        "AlarmClock AluminumFoil Apple ArmChair BaseballBat BasketBall Bathtub BathtubBasin Bed "
        "Blinds Book Boots Bottle Bowl Box Bread ButterKnife Cabinet Candle CD CellPhone Chair "
        "Cloth CoffeeMachine CoffeeTable CounterTop CreditCard Cup Curtains Desk DeskLamp Desktop "
        "DiningTable DishSponge DogBed Door Doorway Drawer Dresser Dumbbell Egg Faucet FloorLamp "
        "Footstool Fork Fridge GarbageBag GarbageCan HandTowel HandTowelHolder HousePlant Kettle "
        "KeyChain Knife Ladle Laptop LaundryHamper Lettuce LightSwitch Microwave Mirror Mug "
        "Newspaper Ottoman Painting Pan PaperTowelRoll Pen Pencil PepperShaker Pillow Plate "
        "Plunger Poster Pot Potato RemoteControl RoomDecor Safe SaltShaker ScrubBrush Shelf "
        "ShelvingUnit ShowerCurtain ShowerDoor ShowerGlass ShowerHead SideTable Sink SinkBasin "
        "SoapBar SoapBottle Sofa Spatula Spoon SprayBottle Statue Stool StoveBurner StoveKnob "
        "TableTopDecor TeddyBear Television TennisRacket TissueBox Toaster Toilet ToiletPaper "
        "ToiletPaperHanger Tomato Towel TowelHolder TVStand VacuumCleaner Vase Watch WateringCan "
        "Window WineBottle"
    )
)

#: Words VLMs use (joined, singular, lower case) -> engine types they may denote, most
#: likely first. Engine type names need no entry (``diningtable`` denotes ``DiningTable``).
SYNONYMS: Final[dict[str, tuple[str, ...]]] = {
    # seating
    "chair": ("Chair",),
    "officechair": ("Chair",),
    "deskchair": ("Chair",),
    "swivelchair": ("Chair",),
    "seat": ("Chair", "Stool", "ArmChair"),
    "armchair": ("ArmChair",),
    "loungechair": ("ArmChair",),
    "easychair": ("ArmChair",),
    "recliner": ("ArmChair",),
    "sofa": ("Sofa", "ArmChair"),
    "couch": ("Sofa", "ArmChair"),
    "loveseat": ("Sofa", "ArmChair"),
    "stool": ("Stool",),
    "barstool": ("Stool",),
    # tables and desks
    "table": ("DiningTable", "CoffeeTable", "SideTable", "Desk"),
    "conferencetable": ("DiningTable",),
    "meetingtable": ("DiningTable",),
    "boardroomtable": ("DiningTable",),
    "longtable": ("DiningTable",),
    "kitchentable": ("DiningTable",),
    "desk": ("Desk",),
    "officedesk": ("Desk",),
    "workstation": ("Desk",),
    "receptiondesk": ("Desk",),
    "frontdesk": ("Desk",),
    "reception": ("Desk",),
    "counter": ("CounterTop", "Desk"),
    "receptioncounter": ("Desk",),
    "kitchencounter": ("CounterTop",),
    "worktop": ("CounterTop",),
    "countertop": ("CounterTop",),
    # storage
    "shelf": ("ShelvingUnit", "Shelf"),
    "shelving": ("ShelvingUnit", "Shelf"),
    "bookshelf": ("ShelvingUnit", "Shelf"),
    "bookcase": ("ShelvingUnit", "Shelf"),
    "cabinet": ("Cabinet", "ShelvingUnit"),
    "filingcabinet": ("Cabinet", "ShelvingUnit"),
    # screens and computers
    "tv": ("Television",),
    "television": ("Television",),
    "televisionset": ("Television",),
    "flatscreen": ("Television",),
    "screen": ("Television", "Laptop"),
    "monitor": ("Television", "Desktop", "Laptop"),
    "display": ("Television",),
    "computer": ("Laptop", "Desktop"),
    "notebook": ("Laptop",),
    "pc": ("Desktop", "Laptop"),
    # plants
    "plant": ("HousePlant",),
    "pottedplant": ("HousePlant",),
    "indoorplant": ("HousePlant",),
    "flowerpot": ("HousePlant",),
    # kitchen
    "fridge": ("Fridge",),
    "refrigerator": ("Fridge",),
    "freezer": ("Fridge",),
    "microwaveoven": ("Microwave",),
    "coffeemaker": ("CoffeeMachine",),
    "espressomachine": ("CoffeeMachine",),
    "coffeemachine": ("CoffeeMachine",),
    "kitchensink": ("Sink",),
    "basin": ("Sink", "SinkBasin"),
    # ways through
    "doorway": ("Doorway",),
    "door": ("Doorway", "Door"),
    "opening": ("Doorway",),
    "passage": ("Doorway",),
    "passageway": ("Doorway",),
    "archway": ("Doorway",),
    "doorframe": ("Doorway",),
    "entryway": ("Doorway",),
    "exit": ("Door",),
    "exitdoor": ("Door",),
    "frontdoor": ("Door",),
    "maindoor": ("Door",),
    "entrancedoor": ("Door",),
    "emergencyexit": ("Door",),
    "fireexit": ("Door",),
    "buildingexit": ("Door",),
}

#: Words that open a qualifier phrase; the label is cut before the first of them.
QUALIFIER_WORDS: Final[frozenset[str]] = frozenset(
    _split(
        "near by next beside besides behind in inside on at under beneath below above against "
        "from with of to toward towards facing opposite between along across left right close "
        "around"
    )
)

_CAMEL = re.compile(r"(?<=[a-z0-9])(?=[A-Z])|(?<=[A-Z])(?=[A-Z][a-z]{2})")
_ASIDE = re.compile(r"\(.*?\)|\[.*?\]|\{.*?\}")
_WORDS = re.compile(r"[a-z]+|[0-9]+")
_TYPE_OF_KEY: Final[dict[str, str]] = {t.lower(): t for t in ENGINE_TYPES}
_MAX_RUN: Final = 4


def _singulars(word: str) -> tuple[str, ...]:
    """``word`` then its plausible singulars (``shelves`` -> ``shelf``, ``couches``)."""
    forms = [word]
    if len(word) > 3 and word.endswith("ves"):
        forms.append(word[:-3] + "f")
    if len(word) > 3 and word.endswith("es"):
        forms.append(word[:-2])
    if len(word) > 2 and word.endswith("s") and not word.endswith("ss"):
        forms.append(word[:-1])
    return tuple(forms)


def _lookup(key: str) -> tuple[str, ...]:
    hit = SYNONYMS.get(key)
    if hit is not None:
        return hit
    engine = _TYPE_OF_KEY.get(key)
    return (engine,) if engine is not None else ()


def head_words(text: str) -> tuple[str, ...]:
    """Step 1 and 3's words: split, lower-cased, instance numbers and letters dropped."""
    spaced = _CAMEL.sub(" ", _ASIDE.sub(" ", text))
    words = _WORDS.findall(spaced.lower())
    return tuple(w for w in words if not w.isdigit() and len(w) > 1)


def _cut(words: tuple[str, ...]) -> tuple[str, ...]:
    """The words before the first qualifier word (not counting the first word)."""
    for i, w in enumerate(words):
        if i > 0 and w in QUALIFIER_WORDS:
            return words[:i]
    return words


@lru_cache(maxsize=8192)
def candidate_types(text: str) -> tuple[str, ...]:
    """Engine types ``text`` may denote, most likely first; ``()`` for none (a hallucination).

    See the module docstring for the procedure. ``candidate_types("table by the door")`` is
    ``("DiningTable", "CoffeeTable", "SideTable", "Desk")``; ``candidate_types("ghost")`` is
    ``()``.
    """
    words = head_words(text)
    cut = _cut(words)
    return _head(cut) or (_head(words) if cut != words else ())


def _head(words: tuple[str, ...]) -> tuple[str, ...]:
    """Candidates of the longest (then rightmost) run of ``words`` naming a type (step 3)."""
    for size in range(min(_MAX_RUN, len(words)), 0, -1):
        for start in range(len(words) - size, -1, -1):
            run = words[start : start + size]
            stem = "".join(run[:-1])
            for last in _singulars(run[-1]):
                hit = _lookup(stem + last)
                if hit:
                    return hit
    return ()


def canonical_type(text: str, *, present: Iterable[str] | None = None) -> str | None:
    """The AI2-THOR ``objectType`` a label or type name written by a model denotes.

    ``canonical_type("office chair") == "Chair"``, ``"TV" -> "Television"``,
    ``"chairs (2)" -> "Chair"``, ``"small wooden table by the door" -> "DiningTable"``,
    ``"the red armchair" -> "ArmChair"``, ``"fire extinguisher" -> None``.

    ``present``: the types a layout holds. Given, the first candidate among them wins
    (``canonical_type("table", present={"Desk"}) == "Desk"``) and None is returned when the
    layout holds none of the candidates. Without it, the most likely engine type is returned.
    None means the text names no engine type (or none the layout holds): a hallucination.
    """
    candidates = candidate_types(text)
    if present is None:
        return candidates[0] if candidates else None
    held = set(present)
    return next((c for c in candidates if c in held), None)


class TypeResolver:
    """Resolves written type names to the index of a ground-truth type of one episode."""

    def __init__(self, types: Iterable[str]) -> None:
        self.names: list[str] = sorted(set(types))
        """Ground-truth types, sorted; a type's index is its position here."""
        self.index: dict[str, int] = {t: i for i, t in enumerate(self.names)}
        self._lower = {t.lower(): t for t in self.names}
        self.known: dict[tuple[str, str], int] = {}
        """``(object_type, label)`` -> type index, for every entry resolved so far."""

    def resolve(self, object_type: str, label: str) -> int:
        """Type index of an entry (its ``object_type`` first, then its label); -1 if none."""
        hit = self.known.get((object_type, label))
        if hit is None:
            hit = self._resolve_text(object_type)
            if hit < 0:
                hit = self._resolve_text(label)
            self.known[(object_type, label)] = hit
        return hit

    def _resolve_text(self, text: str) -> int:
        if text in self.index:
            return self.index[text]
        found = canonical_type(text, present=self.index)
        if found is None:  # a layout type outside the engine vocabulary, written as named
            found = self._lower.get("".join(head_words(text)))
        return -1 if found is None else self.index[found]
