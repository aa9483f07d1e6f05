"""The data behind every figure, computed from grouped episode metrics (pure)."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence

import numpy as np

from pytest_emrd.errors import ConfigError
from pytest_emrd.metrics import (
    Ebbinghaus,
    EpisodeMetrics,
    Matching,
    kaplan_meier_anchored,
    match_map,
    miller_curve,
    positional_accuracy,
    rigid_fit,
    spatial_identity_resolution,
    tbs_curve,
)
from pytest_emrd.report._model import (
    EpisodeMap,
    KMSeries,
    MapPoint,
    MillerSeries,
    PASpawn,
    SIRSeries,
    TBSSeries,
)
from pytest_emrd.report._tables import Cells
from pytest_emrd.run import StoredEpisode
from pytest_emrd.trajectory import MapEntry, Trajectory


def tbs_series(cells: Cells) -> tuple[TBSSeries, ...]:
    return tuple(TBSSeries(m, v, c, tbs_curve(ems)) for (m, v, c), ems in cells.items())


def pa_by_spawn(cells: Cells) -> tuple[PASpawn, ...]:
    """Per-episode Positional Accuracy grouped by spawn room (``positional_accuracy``)."""
    out = []
    for (model, variant, condition), ems in cells.items():
        by_spawn: dict[str, list[EpisodeMetrics]] = {}
        for m in ems:
            by_spawn.setdefault(m.spec.spawn, []).append(m)
        for spawn, group in by_spawn.items():
            values = tuple(v for v in positional_accuracy(group) if v is not None)
            out.append(PASpawn(model, variant, condition, spawn, values))
    return tuple(out)


def miller_series(cells: Cells) -> tuple[MillerSeries, ...]:
    return tuple(MillerSeries(m, v, c, miller_curve(ems)) for (m, v, c), ems in cells.items())


def km_series(
    cells: Cells, fits: Mapping[tuple[str, str, str], Ebbinghaus]
) -> tuple[KMSeries, ...]:
    """Anchored KM per category with the Ebbinghaus fit of the same category (``fits``: the
    cells' :func:`~pytest_emrd.metrics.ebbinghaus`, computed once for their table)."""
    out = []
    for key, ems in cells.items():
        model, variant, condition = key
        by_category = fits[key].by_category
        for category, km in kaplan_meier_anchored(ems).items():
            out.append(KMSeries(model, variant, condition, category, km, by_category[category]))
    return tuple(out)


def sir_series(cells: Cells) -> tuple[SIRSeries, ...]:
    return tuple(
        SIRSeries(m, v, c, spatial_identity_resolution(ems)) for (m, v, c), ems in cells.items()
    )


def pick_episode(
    episodes: Sequence[StoredEpisode], case_id: str | None = None
) -> StoredEpisode | None:
    """The episode the map figure shows: ``case_id`` when given (a :class:`ConfigError` naming
    a few of the run's case ids when the run has no such episode), else the first non-errored
    one (baseline first, case-id order) whose terminal map holds an entry; None when there is
    none. Chosen from the episodes' heads: no trajectory is decoded."""
    heads = [e.head for e in episodes]
    if case_id is not None:
        found = [e for e, h in zip(episodes, heads, strict=True) if h.spec.case_id == case_id]
        if not found:
            held = sorted(h.spec.case_id for h in heads)
            shown = ", ".join(held[:3]) + (", ..." if len(held) > 3 else "")
            raise ConfigError(
                f"episode={case_id!r} is not in the run ({len(held)} episodes: {shown}); "
                "pass a case id as the test ids show it, e.g. scout-baseline-office-ep00."
            )
        return found[0]
    candidates = [
        (h.spec.condition != "baseline", h.spec.case_id, i)
        for i, h in enumerate(heads)
        if h.status != "errored" and h.final_map_entries
    ]
    return episodes[min(candidates)[2]] if candidates else None


def align_map(
    entries: Sequence[MapEntry], matching: Matching
) -> tuple[tuple[MapPoint, ...], float, float | None]:
    """A cognitive map moved by :func:`rigid_fit` of its matched pairs onto the ground truth
    (unmatched entries move with it; a repeated label is shown once): the points, the fit's
    rotation in degrees and the RMS residual of the pairs (None without pairs)."""
    matched = {p.label: p for p in matching.pairs}
    rot, shift = np.eye(2), np.zeros(2)
    rmse = None
    if matching.pairs:
        pred = np.array([(p.pred_x, p.pred_z) for p in matching.pairs])
        true = np.array([(p.true_x, p.true_z) for p in matching.pairs])
        rot, shift = rigid_fit(pred, true)
        rmse = float(np.sqrt(np.mean(np.sum((pred @ rot.T + shift - true) ** 2, axis=1))))
    seen: set[str] = set()
    points = []
    for e in entries:
        if e.label in seen:
            continue
        seen.add(e.label)
        x, z = np.array([e.x, e.z]) @ rot.T + shift
        pair = matched.get(e.label)
        points.append(MapPoint(e.label, float(x), float(z), pair.object_id if pair else None))
    return tuple(points), math.degrees(math.atan2(rot[1, 0], rot[0, 0])), rmse


def episode_map(traj: Trajectory) -> EpisodeMap:
    """Ground truth, path and the terminal map aligned by :func:`align_map` on the pairs of
    :func:`match_map`."""
    truth = traj.ground_truth
    points, rotation, rmse = align_map(traj.final_map, match_map(traj.final_map, truth.objects))
    return EpisodeMap(
        case_id=traj.spec.case_id,
        rooms=truth.rooms,
        objects=truth.objects,
        path=tuple((s.pose.x, s.pose.z) for s in traj.steps),
        entries=points,
        rotation_deg=rotation,
        rmse=rmse,
    )
