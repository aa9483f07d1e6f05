"""Which episodes validation needs: one group of episodes per planted agent and condition.

Pure data, read back by group name. Every group runs the same offices (``EpisodeSpec.seed``
depends on spawn room and episode index only), so groups are paired episode by episode.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Final

from pytest_emrd.errors import check_positive_int
from pytest_emrd.rooms import ROOM_SLUGS
from pytest_emrd.trajectory import EpisodeSpec

#: Planted exponential retention means (steps) whose recovery the Ebbinghaus rows check.
DECAY_MEANS: Final = (3, 8, 20)
#: Planted working-memory capacities whose recovery the Miller rows check.
WINDOW_SIZES: Final = (5, 10, 20)
#: Knobs of the mimic groups: each moves one planted behaviour away from the clean mimic.
MIMIC_SIGMA: Final = 0.3
MIMIC_DUP: Final = 0.5
MIMIC_HALLUC: Final = 0.1
#: The mimic group of each role: the clean mimic in the spawn frame and in its own frame, one
#: knob moved at a time, and the shipped defaults. The knob groups walk back into the room
#: they name (``b1``), so every episode re-enters a room and SIR is defined.
MIMIC_MODELS: Final = {
    "spawn": "mimic-spawn-s0-p0-h0-q0-r0-a0-b1",
    "own": "mimic-s0-p0-h0-q0-r0-a0-b1",
    "sigma": f"mimic-s{MIMIC_SIGMA:g}-p0-h0-q0-r0-a0-b1",
    "dup": f"mimic-s0-p{MIMIC_DUP:g}-h0-q0-r0-a0-b1",
    "halluc": f"mimic-s0-p0-h{MIMIC_HALLUC:g}-q0-r0-a0-b1",
    "default": "mimic",
}
#: Reference agents run in the symbolic modality they are registered with.
MODALITY: Final = "both"
#: Episodes per spawn room of the full run (the paper's 20 per spawn, 80 per model).
FULL_EPISODES: Final = 20


@dataclass(frozen=True)
class Group:
    """Episodes of one planted agent under one condition, over every spawn room."""

    model: str
    """Registry name of the reference agent (``scout-decay-8``)."""
    condition: str
    layouts: str = "paper"
    """``paper`` (the fixed office) or ``generated`` (an office per spawn x episode)."""

    @property
    def name(self) -> str:
        """``scout-decay-8`` under baseline, ``scout@low_light`` otherwise; ``@generated``
        appended on generated layouts."""
        name = self.model if self.condition == "baseline" else f"{self.model}@{self.condition}"
        return name if self.layouts == "paper" else f"{name}@{self.layouts}"

    def specs(self, episodes: int) -> tuple[EpisodeSpec, ...]:
        """``episodes`` episodes per spawn room, spawn-major."""
        return tuple(
            EpisodeSpec(
                self.model, self.condition, spawn, k, modality=MODALITY, layouts=self.layouts
            )
            for spawn in ROOM_SLUGS.values()
            for k in range(episodes)
        )


SCOUT_GROUPS: Final = (
    Group("scout", "baseline"),
    Group("scout", "low_light"),
    *(Group(f"scout-decay-{m}", "baseline") for m in DECAY_MEANS),
    *(Group(f"scout-window-{k}", "baseline") for k in WINDOW_SIZES),
    Group("scout-serial", "baseline"),
    Group("prior", "baseline"),
)
#: The knob groups run on generated offices (many layouts test the frame, noise and
#: duplicate rows harder than one); the default mimic runs the benchmark's own office.
MIMIC_GROUPS: Final = tuple(
    Group(m, "baseline", "paper" if role == "default" else "generated")
    for role, m in MIMIC_MODELS.items()
)
#: Agent families ``emrd validate --family`` selects: scout (with ``prior``) and mimic.
FAMILIES: Final = {"scout": SCOUT_GROUPS, "mimic": MIMIC_GROUPS}
GROUPS: Final = SCOUT_GROUPS + MIMIC_GROUPS


@dataclass(frozen=True)
class Plan:
    """Every episode of a validation run."""

    episodes: int
    """Episodes per spawn room and group."""
    groups: tuple[Group, ...] = GROUPS

    def __post_init__(self) -> None:
        check_positive_int("episodes", self.episodes)

    def specs(self) -> tuple[EpisodeSpec, ...]:
        return tuple(s for g in self.groups for s in g.specs(self.episodes))
