"""The report model: every table and figure of a report as plain, JSON-able data, and for every
renderer the conditions' names and the list of figures (:data:`FIGURES`).

The numbers inside are the metrics library's own result objects
(:class:`~pytest_emrd.metrics.Estimate`, ...), never re-derived, so a report and a direct call
of the library agree by construction. Fractions are in [0, 1]; renderers turn them into %. Rows
are keyed by ``model``, ``variant`` (prompt variant) and, where the paper splits by it,
``condition``. Field names are the JSON format; bump :data:`SCHEMA_VERSION` on any change.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Final

import numpy as np

from pytest_emrd import metrics
from pytest_emrd._serde import JsonRecord, Schema
from pytest_emrd.gate import UsageRow, Verdict
from pytest_emrd.trajectory import GroundTruthObject, RoomOutline

SCHEMA_VERSION: Final = 1


def row_label(model: str, variant: str) -> str:
    """``gemini`` for the default prompt, ``gemini [B3]`` for a prompt variant.

    :param model: The model name.
    :param variant: The prompt variant.
    :returns: The row label.
    """
    return model if variant == "default" else f"{model} [{variant}]"


#: The paper's names of the conditions.
CONDITION_NAMES: Final[dict[str, str]] = {
    "baseline": "Baseline",
    "low_light": "Light & Vis.",
    "texture": "Texture & Col.",
}


def rank(value: str, order: Sequence[str]) -> tuple[int, str]:
    """Sort key: the place in the paper's ``order``; values it lacks after it, by name."""
    return (order.index(value) if value in order else len(order), value)


@dataclass(frozen=True)
class Overview:
    """What the run holds."""

    episodes: int
    by_status: dict[str, int]
    """``terminated`` / ``budget`` / ``errored`` -> episodes."""
    models: tuple[str, ...]
    conditions: tuple[str, ...]
    """In the paper's order (baseline, low_light, texture)."""
    variants: tuple[str, ...]
    spawns: tuple[str, ...]
    usage: tuple[UsageRow, ...]
    """Tokens (and estimated cost where prices are known) per model."""


@dataclass(frozen=True)
class CellRow:
    """A row of one report cell: model x prompt variant x condition."""

    model: str
    variant: str
    condition: str

    @property
    def label(self) -> str:
        """The model row it belongs to (:func:`row_label`)."""
        return row_label(self.model, self.variant)


@dataclass(frozen=True)
class ExplorationRow(CellRow):
    """Exploration Competence of one cell (paper Table AEC/TE)."""

    aec: metrics.Estimate
    """``GATE_METRICS['aec']`` over the cell (mean, bootstrap CI, n)."""
    aec_sd: float | None
    """Sample standard deviation of the per-episode AEC (None when n < 2)."""
    te: metrics.Estimate
    te_sd: float | None


@dataclass(frozen=True)
class FocalTable(CellRow):
    """Chosen-room distribution by spawn of one model x variant x condition."""

    distribution: metrics.FocalDistribution
    consensus: metrics.Consensus


@dataclass(frozen=True)
class FPSGRow(CellRow):
    summary: metrics.FPSGSummary


@dataclass(frozen=True)
class EbbinghausRow(CellRow):
    fit: metrics.Ebbinghaus


@dataclass(frozen=True)
class SerialRow(CellRow):
    spe: metrics.SerialPosition


@dataclass(frozen=True)
class AnovaRow:
    """One-way ANOVA of per-episode memory strength across conditions, per model x variant."""

    model: str
    variant: str
    anova: metrics.Anova


@dataclass(frozen=True)
class VariantTest:
    """One prompt variant against the ``default`` prompt (same model and condition)."""

    variant: str
    choices: metrics.FocalRow
    """Chosen-room letters of the variant's episodes."""
    fisher: metrics.FisherExact | None
    """Conference Room vs any other choice, variant vs default (None: a group is empty)."""
    chi_square: metrics.ChiSquare
    """Pearson chi-square over the full C/O/K/E/X distribution, default vs variant."""
    cramers_v: float | None


@dataclass(frozen=True)
class InterventionTable:
    """The paper's controlled-intervention table for one model x condition."""

    model: str
    condition: str
    reference: metrics.FocalRow
    """Chosen-room letters under the ``default`` prompt."""
    variants: tuple[VariantTest, ...]
    overall: metrics.ChiSquare | None
    """Conference vs other over ``default`` + the B1-B4 variants present (None: no B variant)."""
    overall_variants: tuple[str, ...]
    """Groups in ``overall``, ``default`` first."""


@dataclass(frozen=True)
class ReasoningRow:
    model: str
    representative: metrics.Representative


@dataclass(frozen=True)
class Reasoning:
    """Most representative terminal reasoning per model (all conditions pooled, as the paper)."""

    rows: tuple[ReasoningRow, ...]
    unavailable: str | None = None
    """Why the table is absent (e.g. the ``nlp`` extra is missing, with the pip command)."""


@dataclass(frozen=True)
class Gates:
    """Gate verdicts of the run against a thresholds file."""

    source: str | None
    """The thresholds file, or None when no file was given or found."""
    verdicts: tuple[Verdict, ...]
    note: str | None = None
    """Why no gate ran, where the caller knows (a shard's gates run in ``emrd gate``)."""


@dataclass(frozen=True)
class TBSSeries(CellRow):
    curve: metrics.TBSCurve


@dataclass(frozen=True)
class PASpawn(CellRow):
    """Per-episode Positional Accuracy of one model x variant x condition x spawn room."""

    spawn: str
    values: tuple[float, ...]
    """``positional_accuracy`` of each episode where it is defined, in case-id order."""

    @property
    def mean_sd(self) -> tuple[float | None, float | None]:
        """Mean and sample standard deviation of :attr:`values` (None without values; the sd
        None with one value)."""
        n = len(self.values)
        sd = float(np.std(self.values, ddof=1)) if n > 1 else None
        return (float(np.mean(self.values)) if n else None), sd


@dataclass(frozen=True)
class MillerSeries(CellRow):
    curve: metrics.MillerCurve


@dataclass(frozen=True)
class KMSeries(CellRow):
    """Coverage-anchored KM of one category, with its Ebbinghaus fit."""

    category: str
    km: metrics.AnchoredKM
    fit: metrics.EbbinghausFit


@dataclass(frozen=True)
class SIRSeries(CellRow):
    sir: metrics.SpatialIdentityResolution


@dataclass(frozen=True)
class MapPoint:
    """One entry of the terminal cognitive map, rigidly aligned onto the ground truth."""

    label: str
    x: float
    z: float
    object_id: str | None
    """The ground-truth object it was matched to, None when unmatched or unrecognised."""


@dataclass(frozen=True)
class EpisodeMap:
    """Top-down view of one episode: ground truth, path and the aligned terminal map."""

    case_id: str
    rooms: tuple[RoomOutline, ...]
    objects: tuple[GroundTruthObject, ...]
    path: tuple[tuple[float, float], ...]
    """Agent position at each step (spawn frame, metres)."""
    entries: tuple[MapPoint, ...]
    rotation_deg: float
    """Rotation of the rigid fit (degrees, counter-clockwise in the x-z plane)."""
    rmse: float | None
    """RMS residual of the matched entries after alignment (m); None without matches."""


@dataclass(frozen=True)
class Report(JsonRecord):
    """Every table and figure of one report."""

    schema = Schema(
        SCHEMA_VERSION, "report", "rebuild the report from the run directory with `emrd report`."
    )

    overview: Overview
    missing: tuple[str, ...]
    """What the run lacks for a complete report, one sentence each."""
    exploration: tuple[ExplorationRow, ...]
    focal: tuple[FocalTable, ...]
    fpsg: tuple[FPSGRow, ...]
    ebbinghaus: tuple[EbbinghausRow, ...]
    serial_position: tuple[SerialRow, ...]
    anova: tuple[AnovaRow, ...]
    interventions: tuple[InterventionTable, ...]
    reasoning: Reasoning
    gates: Gates
    tbs: tuple[TBSSeries, ...]
    pa: tuple[PASpawn, ...]
    miller: tuple[MillerSeries, ...]
    km: tuple[KMSeries, ...]
    sir: tuple[SIRSeries, ...]
    episode_map: EpisodeMap | None
    schema_version: int = SCHEMA_VERSION


@dataclass(frozen=True)
class FigureSpec:
    """A report figure: file name, title and what it shows."""

    name: str
    title: str
    caption: str


FIGURES: Final[tuple[FigureSpec, ...]] = (
    FigureSpec(
        "tbs.png",
        "Temporal Belief Stability",
        "Mean TBS(t) per step (band: ± 1 sd across episodes; Eq. TBS).",
    ),
    FigureSpec(
        "pa_by_spawn.png",
        "Positional Accuracy by spawn room and condition",
        "Mean per-episode PA (Eq. PA) with ± 1 sd, per spawn room.",
    ),
    FigureSpec(
        "miller.png",
        "Miller's law: forgetting probability by load",
        "Share of steps that lose at least one mapped object, by map size (bins of w).",
    ),
    FigureSpec(
        "km.png",
        "Coverage-anchored Kaplan-Meier survival per category",
        "Anchored KM (steps) with the Ebbinghaus curve C exp(-t / EFC) dashed.",
    ),
    FigureSpec(
        "sir.png",
        "Spatial Identity Resolution",
        "Per-episode SIR on room re-entry (episodes with a re-entry).",
    ),
    FigureSpec(
        "episode_map.png",
        "One episode, top down",
        "Ground truth, the agent's path and its terminal map after rigid alignment.",
    ),
)
