"""Which episodes validation needs: one group of episodes per planted agent and condition.

Pure data: the runner (:mod:`._run`) turns a :class:`Plan` into trajectories, the checks
read them back by group name. Every group runs the same offices (``EpisodeSpec.seed``
depends on spawn room and episode index only), so groups are paired episode by episode.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Final

from pytest_emrd.errors import check_positive_int
from pytest_emrd.rooms import ROOM_SLUGS
from pytest_emrd.trajectory import EpisodeSpec

#: Planted exponential retention means (steps) whose recovery the Ebbinghaus rows check.
DECAY_MEANS: Final[tuple[int, ...]] = (3, 8, 20)
#: Planted working-memory capacities whose recovery the Miller rows check.
WINDOW_SIZES: Final[tuple[int, ...]] = (5, 10, 20)
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

    @property
    def name(self) -> str:
        """``scout-decay-8`` under baseline, ``scout@low_light`` otherwise."""
        return self.model if self.condition == "baseline" else f"{self.model}@{self.condition}"

    def specs(self, episodes: int) -> tuple[EpisodeSpec, ...]:
        """``episodes`` episodes per spawn room, spawn-major."""
        return tuple(
            EpisodeSpec(self.model, self.condition, spawn, k, modality=MODALITY)
            for spawn in ROOM_SLUGS.values()
            for k in range(episodes)
        )


GROUPS: Final[tuple[Group, ...]] = (
    Group("scout", "baseline"),
    Group("scout", "low_light"),
    *(Group(f"scout-decay-{m}", "baseline") for m in DECAY_MEANS),
    *(Group(f"scout-window-{k}", "baseline") for k in WINDOW_SIZES),
    Group("scout-serial", "baseline"),
    Group("prior", "baseline"),
)


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
