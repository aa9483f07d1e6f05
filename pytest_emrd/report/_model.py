"""The report model: every table and figure of a report as plain, JSON-able data.

Computed by :func:`~pytest_emrd.report.build_report` from trajectories (pure) and rendered to
Markdown, HTML, JSON and PNG by the rendering modules. The numbers inside are the metrics
library's own result objects (:class:`~pytest_emrd.metrics.Estimate`,
:class:`~pytest_emrd.metrics.FPSGSummary`, ...), never re-derived, so a report and a direct call
of the library agree by construction. Fractions are in [0, 1]; renderers turn them into %.

Rows are keyed by ``model``, ``variant`` (prompt variant) and, where the paper splits by it,
``condition``. Field names are the JSON format; bump :data:`SCHEMA_VERSION` on any change.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Final

from pytest_emrd._serde import from_versioned_dict, to_dict
from pytest_emrd.gate import UsageRow, Verdict
from pytest_emrd.metrics import (
    AnchoredKM,
    Anova,
    ChiSquare,
    Consensus,
    Ebbinghaus,
    EbbinghausFit,
    Estimate,
    FisherExact,
    FocalDistribution,
    FocalRow,
    FPSGSummary,
    MillerCurve,
    Representative,
    SerialPosition,
    SpatialIdentityResolution,
    TBSCurve,
)
from pytest_emrd.trajectory import GroundTruthObject, RoomOutline

SCHEMA_VERSION: Final = 1


def row_label(model: str, variant: str) -> str:
    """``gemini`` for the default prompt, ``gemini [B3]`` for a prompt variant."""
    return model if variant == "default" else f"{model} [{variant}]"


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
class ExplorationRow:
    """Exploration Competence of one model x variant x condition (paper Table AEC/TE)."""

    model: str
    variant: str
    condition: str
    aec: Estimate
    """``GATE_METRICS['aec']`` over the cell (mean, bootstrap CI, n)."""
    aec_sd: float | None
    """Sample standard deviation of the per-episode AEC (None when n < 2)."""
    te: Estimate
    te_sd: float | None


@dataclass(frozen=True)
class FocalTable:
    """Chosen-room distribution by spawn of one model x variant x condition."""

    model: str
    variant: str
    condition: str
    distribution: FocalDistribution
    consensus: Consensus


@dataclass(frozen=True)
class FPSGRow:
    model: str
    variant: str
    condition: str
    summary: FPSGSummary


@dataclass(frozen=True)
class EbbinghausRow:
    model: str
    variant: str
    condition: str
    fit: Ebbinghaus


@dataclass(frozen=True)
class SerialRow:
    model: str
    variant: str
    condition: str
    spe: SerialPosition


@dataclass(frozen=True)
class AnovaRow:
    """One-way ANOVA of per-episode memory strength across conditions, per model x variant."""

    model: str
    variant: str
    anova: Anova


@dataclass(frozen=True)
class VariantTest:
    """One prompt variant against the ``default`` prompt (same model and condition)."""

    variant: str
    choices: FocalRow
    """Chosen-room letters of the variant's episodes."""
    fisher: FisherExact | None
    """Conference Room vs any other choice, variant vs default (None: a group is empty)."""
    chi_square: ChiSquare
    """Pearson chi-square over the full C/O/K/E/X distribution, default vs variant."""
    cramers_v: float | None


@dataclass(frozen=True)
class InterventionTable:
    """The paper's controlled-intervention table for one model x condition."""

    model: str
    condition: str
    reference: FocalRow
    """Chosen-room letters under the ``default`` prompt."""
    variants: tuple[VariantTest, ...]
    overall: ChiSquare | None
    """Conference vs other over ``default`` + the B1-B4 variants present (None: no B variant)."""
    overall_variants: tuple[str, ...]
    """Groups in ``overall``, ``default`` first."""


@dataclass(frozen=True)
class ReasoningRow:
    model: str
    representative: Representative


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


@dataclass(frozen=True)
class TBSSeries:
    model: str
    variant: str
    condition: str
    curve: TBSCurve


@dataclass(frozen=True)
class PASpawn:
    """Per-episode Positional Accuracy of one model x variant x condition x spawn room."""

    model: str
    variant: str
    condition: str
    spawn: str
    values: tuple[float, ...]
    """``positional_accuracy`` of each episode where it is defined, in case-id order."""


@dataclass(frozen=True)
class MillerSeries:
    model: str
    variant: str
    condition: str
    curve: MillerCurve


@dataclass(frozen=True)
class KMSeries:
    """Coverage-anchored KM of one category, with its Ebbinghaus fit."""

    model: str
    variant: str
    condition: str
    category: str
    km: AnchoredKM
    fit: EbbinghausFit


@dataclass(frozen=True)
class SIRSeries:
    model: str
    variant: str
    condition: str
    sir: SpatialIdentityResolution


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
class Report:
    """Every table and figure of one report."""

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

    def to_dict(self) -> dict[str, Any]:
        return to_dict(self)

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> Report:
        return from_versioned_dict(
            cls,
            data,
            version=SCHEMA_VERSION,
            what="report",
            remedy="rebuild the report from the run directory with `emrd report`.",
        )
