"""The record of one episode: what the episode loop writes and every metric reads.

A :class:`Trajectory` is plain data, stored as JSON; field names are the file format (bump
:data:`SCHEMA_VERSION` on any incompatible change).

Coordinates are in the *spawn frame*, the frame the agent is told its pose in: origin at the
spawn position, ``+z`` along the initial heading, ``+x`` to its right, metres; headings are
degrees clockwise from ``+z``. The model's map coordinates are whatever it wrote; metrics
align them with Procrustes and never trust the frame.

Timeline of step ``t`` (1-based): the agent is shown ``o_{t-1}`` (its pose, room and visible
objects are recorded in the step), replies with map ``M_t`` and action ``a_t``; the world
executes ``a_t`` (``success``/``feedback``).
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass, field
from typing import Final

from pytest_emrd._serde import JsonRecord, Schema

SCHEMA_VERSION: Final = 2
#: Schema versions still read (their missing fields take the defaults): 1 lacks ``Step.repairs``.
OLDER_SCHEMAS: Final[tuple[int, ...]] = (1,)

CONDITIONS: Final[tuple[str, ...]] = ("baseline", "low_light", "texture")
VARIANTS: Final[tuple[str, ...]] = ("default", "B1", "B2", "B3", "B4", "neutral", "no_inventory")
MODALITIES: Final[tuple[str, ...]] = ("vision", "text", "both")
#: Which offices a run uses: ``paper`` (one fixed office, the paper's protocol) or
#: ``generated`` (one generated office per spawn x episode, reported as its own cells).
LAYOUTS: Final[tuple[str, ...]] = ("paper", "generated")
#: The cassette record modes (vcrpy's, ``none`` replays only) and how a replayed request is
#: matched to its recording (``lenient`` ignores frame pixels).
RECORD_MODES: Final[tuple[str, ...]] = ("none", "once", "new_episodes", "all")
MATCHING_MODES: Final[tuple[str, ...]] = ("strict", "lenient")
CATEGORIES: Final[tuple[str, ...]] = ("landmark", "salient", "clutter")
MAX_STEPS: Final = 50


@dataclass(frozen=True)
class EpisodeSpec:
    """Which episode to run; everything about an episode follows from this.

    The world seed depends on spawn room and episode index only, so every model, condition
    and variant sees the same world for the same ``(spawn, episode)``: that pairing lets
    conditions be compared and ``G_base`` be anchored.
    """

    model: str
    """Registry name of the model (``gemini``, ``scout``, ``scout-decay-8`` ...)."""
    condition: str
    """Environmental condition: ``baseline``, ``low_light`` or ``texture``."""
    spawn: str
    """Slug of the spawn room (``office``, ``conference``, ``kitchen``, ``entrance``)."""
    episode: int
    """Episode index within the spawn room, from 0."""
    variant: str = "default"
    """Prompt variant: ``default``, ``B1``..``B4``, ``neutral``, ``no_inventory``."""
    modality: str = "vision"
    """What the agent is shown: ``vision`` frames, ``text`` symbolic list, or ``both``."""
    backend: str = "builtin"
    """World backend: ``builtin`` (numpy) or ``ai2thor``."""
    max_steps: int = MAX_STEPS
    """Action budget ``T_max``."""
    layouts: str = "paper"
    """``paper`` or ``generated`` (:data:`LAYOUTS`)."""

    @property
    def seed(self) -> int:
        """Episode seed (spawn pose, texture colours, and the office under ``generated``),
        shared across models, conditions and variants."""
        digest = hashlib.sha256(f"emrd-world\x1f{self.spawn}\x1f{self.episode}".encode()).digest()
        return int.from_bytes(digest[:4], "big")

    @property
    def case_id(self) -> str:
        """Readable test id: ``gemini-low_light-kitchen-ep07``, with the variant if not default
        and ``generated`` under generated layouts inserted before the spawn room."""
        parts = [self.model, self.condition]
        if self.variant != "default":
            parts.append(self.variant)
        if self.layouts != "paper":
            parts.append(self.layouts)
        parts += [self.spawn, f"ep{self.episode:02d}"]
        return "-".join(parts)


@dataclass(frozen=True)
class GroundTruthObject:
    """One physical object of the office, as the engine knows it."""

    object_id: str
    """Engine instance id, ``Type_N`` (``Chair_3``, ``Doorway_1``)."""
    object_type: str
    """AI2-THOR ``objectType`` name (``Chair``, ``DiningTable``, ``Doorway``)."""
    room: str
    """Canonical room name containing the object (a doorway belongs to its first room)."""
    category: str
    """Memory category: ``landmark``, ``salient`` or ``clutter``."""
    x: float
    """Centre, spawn frame, metres."""
    z: float
    """Centre, spawn frame, metres."""


@dataclass(frozen=True)
class RoomOutline:
    """A room's floor polygon in the spawn frame (for plots and room look-ups)."""

    name: str
    polygon: tuple[tuple[float, float], ...]


@dataclass(frozen=True)
class GroundTruth:
    """The engine's truth for one episode."""

    objects: tuple[GroundTruthObject, ...]
    """Every object of the layout (the set ``E``)."""
    rooms: tuple[RoomOutline, ...]
    """The four rooms."""
    discoverable_ids: tuple[str, ...]
    """``G_base``: ids discoverable under the unperturbed baseline (sorted)."""
    spawn_room: str
    """Canonical name of the spawn room."""


@dataclass(frozen=True)
class Pose:
    """Agent pose in the spawn frame."""

    x: float
    z: float
    heading: float
    """Degrees clockwise from the initial heading, in [0, 360)."""


@dataclass(frozen=True)
class MapEntry:
    """One entry of the model's JSON cognitive map, as parsed."""

    label: str
    """The key the model used (``Desk_1``, ``red chair``)."""
    object_type: str
    """The ``type`` the model wrote (may be empty; metrics fall back to the label)."""
    x: float
    z: float
    room: str | None = None
    """Room the model placed the object in, verbatim (may be an alias such as ``Room A``)."""
    facing: str | None = None


@dataclass(frozen=True)
class Usage:
    """Token usage returned by the provider."""

    prompt_tokens: int = 0
    completion_tokens: int = 0

    def __add__(self, other: Usage) -> Usage:
        return Usage(
            self.prompt_tokens + other.prompt_tokens,
            self.completion_tokens + other.completion_tokens,
        )


@dataclass(frozen=True)
class Step:
    """One decision cycle: observation shown, reply, and the action's outcome."""

    index: int
    """1-based step number ``t``."""
    pose: Pose
    """Agent pose when the observation was shown."""
    room: str
    """Ground-truth room the agent stood in when the observation was shown."""
    visible_ids: tuple[str, ...]
    """Ground-truth ids visible in the observation shown (sorted)."""
    cognitive_map: tuple[MapEntry, ...]
    """The model's map ``M_t`` after this step. On a parse failure, the previous map."""
    action: str
    """The action text the model emitted (``Goto(Doorway_1)``); empty if unreadable."""
    success: bool
    """Whether the engine executed the action."""
    feedback: str
    """Engine feedback on the action (why it failed, where the agent is now)."""
    parse_error: str | None = None
    """Why the reply could not be read, if it could not; the step is still consumed."""
    raw_reply: str = ""
    """The model's reply text, verbatim."""
    usage: Usage = field(default_factory=Usage)
    repairs: tuple[str, ...] | None = None
    """Repairs the parser applied to read the reply, in the order of
    :data:`pytest_emrd.agent.REPAIRS`; ``()`` for a reply read as written; None when not
    recorded (schema 1 files, hand-built steps)."""
    latency_s: float | None = field(default=None, compare=False)
    """Wall time of this step's request in seconds, retries included; None when a cassette
    answered or not recorded. Not compared: a replay equals its recording."""


@dataclass(frozen=True)
class Trajectory(JsonRecord):
    """Everything the metrics need from one episode."""

    schema = Schema(
        SCHEMA_VERSION,
        "trajectory",
        "re-run the episode with this version of pytest-emrd.",
        OLDER_SCHEMAS,
    )

    spec: EpisodeSpec
    protocol: str
    """World + prompt protocol version the episode ran under."""
    ground_truth: GroundTruth
    steps: tuple[Step, ...]
    status: str
    """``terminated`` (the model issued ``Term(r)``, whatever ``r``), ``budget`` (T_max spent
    without a Term) or ``errored``."""
    final_room: str
    """Ground-truth room the agent stands in after its last action."""
    chosen_room: str | None = None
    """Canonical room named by Term (aliases resolved), or None: no Term (``budget``), or a
    Term naming something outside the four rooms (``terminated``, focal column X)."""
    chosen_room_raw: str | None = None
    """The room text the model put in Term, verbatim (kept for X: what it named instead)."""
    rationale: str | None = None
    """The model's terminal ``reasoning``."""
    error: str | None = None
    """Cause when ``status == 'errored'`` (transport exhausted, cassette missing, drift)."""
    schema_version: int = SCHEMA_VERSION

    @property
    def rooms_visited(self) -> frozenset[str]:
        """Rooms the agent physically stood in at any time, spawn and final room included."""
        rooms = {s.room for s in self.steps}
        return frozenset(rooms | {self.final_room, self.ground_truth.spawn_room})

    @property
    def final_map(self) -> tuple[MapEntry, ...]:
        """The terminal cognitive map ``M_T`` (empty if no step was taken)."""
        return self.steps[-1].cognitive_map if self.steps else ()

    @property
    def usage(self) -> Usage:
        """Token usage summed over the steps."""
        return sum((s.usage for s in self.steps), Usage())
