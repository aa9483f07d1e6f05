"""The EMRD metrics: Explore, Map, Remember, Decide, and the paper's statistics.

Pure functions over :class:`~pytest_emrd.trajectory.Trajectory` data: no I/O (except loading
the optional sentence encoder), no global state, randomness only from explicit seeds.
Fractions are in [0, 1], never percent; undefined values are None with a reason.
"""

from pytest_emrd.metrics._aggregates import (
    Consensus,
    Ebbinghaus,
    FocalDistribution,
    FocalRow,
    FPSGSummary,
    MillerCurve,
    SerialPosition,
    SpatialIdentityResolution,
    TBSCurve,
    TimeToForget,
    anova_conditions,
    consensus,
    ebbinghaus,
    focal_distribution,
    forgetting_spells,
    fpsg,
    kaplan_meier_anchored,
    miller_curve,
    positional_accuracy,
    serial_position,
    spatial_identity_resolution,
    tbs_curve,
    time_to_forget,
)
from pytest_emrd.metrics._episode import (
    EpisodeMetrics,
    Grounding,
    aec_score,
    as_episode_metrics,
    discovery_thirds,
    episode_metrics,
    grounding_scores,
    hallucination_score,
    pa_coverage,
    positional_accuracy_score,
    precision_score,
    serial_position_bins,
    sir_score,
    te_score,
)
from pytest_emrd.metrics._gates import GATE_METRICS, GateMetric, evaluate_gates
from pytest_emrd.metrics._match import (
    GATE_M,
    MatchedPair,
    Matching,
    match_map,
    random_reframe,
    reframe,
    rigid_fit,
    step_matchings,
)
from pytest_emrd.metrics._reasoning import Representative, representative_reasoning
from pytest_emrd.metrics._stats import (
    R2_POINTS,
    AnchoredKM,
    Anova,
    ChiSquare,
    EbbinghausFit,
    Estimate,
    FisherExact,
    anchored_km,
    anova_groups,
    bootstrap_ci,
    chi_square,
    cramers_v,
    ebbinghaus_fit,
    efc,
    fisher_exact_2x2,
)
from pytest_emrd.metrics._tracking import Spell
from pytest_emrd.metrics._vocab import ENGINE_TYPES, SYNONYMS, candidate_types, canonical_type

__all__ = [
    "ENGINE_TYPES", "GATE_M", "GATE_METRICS", "R2_POINTS", "SYNONYMS", "AnchoredKM", "Anova",
    "ChiSquare", "Consensus", "Ebbinghaus", "EbbinghausFit", "EpisodeMetrics", "Estimate",
    "FPSGSummary", "FisherExact", "FocalDistribution", "FocalRow", "GateMetric", "Grounding",
    "MatchedPair", "Matching", "MillerCurve", "Representative", "SerialPosition",
    "SpatialIdentityResolution", "Spell", "TBSCurve", "TimeToForget", "aec_score", "anchored_km",
    "anova_conditions", "anova_groups", "as_episode_metrics", "bootstrap_ci", "candidate_types",
    "canonical_type", "chi_square", "consensus", "cramers_v", "discovery_thirds", "ebbinghaus",
    "ebbinghaus_fit", "efc", "episode_metrics", "evaluate_gates", "fisher_exact_2x2",
    "focal_distribution", "forgetting_spells", "fpsg", "grounding_scores", "hallucination_score",
    "kaplan_meier_anchored", "match_map", "miller_curve", "pa_coverage", "positional_accuracy",
    "positional_accuracy_score", "precision_score", "random_reframe", "reframe",
    "representative_reasoning", "rigid_fit", "serial_position", "serial_position_bins", "sir_score",
    "spatial_identity_resolution", "step_matchings", "tbs_curve", "te_score", "time_to_forget",
]  # fmt: skip
