"""Which episodes and which gates a run covers, in one deterministic order (pure)."""

from __future__ import annotations

from collections.abc import Callable, Sequence

from pytest_emrd.gate import GateCell, Thresholds
from pytest_emrd.run._settings import SPAWNS, RunSettings
from pytest_emrd.trajectory import CONDITIONS, EpisodeSpec

#: model name -> its modality when ``--emrd-modality`` is not given (the registry default).
ModalityOf = Callable[[str], str]


def cell_specs(
    settings: RunSettings, model: str, condition: str, modality_of: ModalityOf
) -> list[EpisodeSpec]:
    """The episodes of one model x condition cell: spawns x episodes, in grid order.

    :param settings: The run's settings.
    :param model: The cell's model.
    :param condition: The cell's condition.
    :param modality_of: Model name -> default modality.
    :returns: The cell's :class:`EpisodeSpec` list.
    """
    shared = {
        "variant": settings.variant,
        "modality": settings.modality or modality_of(model),
        "backend": settings.backend,
        "layouts": settings.layouts,
    }
    return [
        EpisodeSpec(model, condition, spawn, episode, **shared)
        for spawn in sorted(settings.spawns, key=SPAWNS.index)
        for episode in range(settings.episodes)
    ]


def _cells(settings: RunSettings) -> list[tuple[str, str]]:
    return sorted(settings.cells, key=lambda mc: (mc[0], CONDITIONS.index(mc[1])))


def episode_specs(settings: RunSettings, modality_of: ModalityOf) -> list[EpisodeSpec]:
    """Every episode of the run (all shards), sorted: model, condition, spawn, episode.

    :param settings: The run's settings: models, conditions, spawns, episodes.
    :param modality_of: Default modality per model, as for :func:`cell_specs`.
    :returns: The sorted specs.
    """
    return [
        spec
        for model, condition in _cells(settings)
        for spec in cell_specs(settings, model, condition, modality_of)
    ]


def shard(specs: Sequence[EpisodeSpec], k: int, n: int) -> list[EpisodeSpec]:
    """The k-th of n round-robin slices (1-based): balanced across models and conditions.

    :param specs: Every episode, in grid order.
    :param k: This shard, from 1.
    :param n: The number of shards.
    :returns: The shard's episodes.
    """
    return list(specs[k - 1 :: n])


def gate_cells(settings: RunSettings, thresholds: Thresholds) -> list[GateCell]:
    """One gate per selected model x condition x thresholded metric, in file order: the bounds
    of the run's layouts only (``baseline`` for paper, ``baseline@generated`` for generated).

    :param settings: The run's settings.
    :param thresholds: The gates.
    :returns: The :class:`GateCell` list.
    """
    return [
        GateCell(bound, settings.variant)
        for model, condition in _cells(settings)
        for bound in thresholds.for_cell(model, condition, settings.layouts)
    ]
