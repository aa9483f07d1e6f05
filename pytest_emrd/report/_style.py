"""Shared look of the report: condition colours and names, the list of figures."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Final

CONDITION_COLOURS: Final[dict[str, str]] = {
    "baseline": "#1f5fbf",
    "low_light": "#d62728",
    "texture": "#2ca02c",
}
#: Line style, marker and hatch per condition, so coinciding series stay distinguishable
#: (and the figures read in grey scale): baseline solid with circles, low light dashed with
#: squares, texture dash-dot with triangles.
CONDITION_LINES: Final[dict[str, tuple[str, str, str]]] = {
    "baseline": ("-", "o", ""),
    "low_light": ("--", "s", "//"),
    "texture": ("-.", "^", ".."),
}
CONDITION_NAMES: Final[dict[str, str]] = {
    "baseline": "Baseline",
    "low_light": "Light & Vis.",
    "texture": "Texture & Col.",
}


@dataclass(frozen=True)
class FigureSpec:
    """A report figure: file name, title and what it shows."""

    name: str
    title: str
    caption: str


FIGURES: Final[tuple[FigureSpec, ...]] = (
    FigureSpec("tbs.png", "Temporal Belief Stability",
               "Mean TBS(t) per step (band: ± 1 sd across episodes; Eq. TBS)."),
    FigureSpec("pa_by_spawn.png", "Positional Accuracy by spawn room and condition",
               "Mean per-episode PA (Eq. PA) with ± 1 sd, per spawn room."),
    FigureSpec("miller.png", "Miller's law: forgetting probability by load",
               "Share of steps that lose at least one mapped object, by map size (bins of w)."),
    FigureSpec("km.png", "Coverage-anchored Kaplan-Meier survival per category",
               "Anchored KM (steps) with the Ebbinghaus curve C exp(-t / EFC) dashed."),
    FigureSpec("sir.png", "Spatial Identity Resolution",
               "Per-episode SIR on room re-entry (episodes with a re-entry)."),
    FigureSpec("episode_map.png", "One episode, top down",
               "Ground truth, the agent's path and its terminal map after rigid alignment."),
)  # fmt: skip
