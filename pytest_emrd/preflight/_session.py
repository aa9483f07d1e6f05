"""Which episodes of a session will call a model for real, and their preflight.

The pytest plugin runs this once per model on the controller (the only process, or the
pytest-xdist controller) after collection, before any episode is computed. Episodes that
replay a cassette, or that the run directory already holds, call nobody and are left out.
"""

from __future__ import annotations

import re
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import KW_ONLY, dataclass, field
from pathlib import Path
from typing import Any, Final

from pytest_emrd.cassette import is_live
from pytest_emrd.preflight._check import PreflightReport, preflight
from pytest_emrd.trajectory import CONDITIONS, EpisodeSpec


def live_grid(
    specs: Iterable[EpisodeSpec],
    *,
    cassettes: Path,
    record_mode: str,
    holds: Callable[[EpisodeSpec], bool],
    modality_of: Callable[[str], str] | None = None,
) -> dict[str, list[EpisodeSpec]]:
    """Model -> its episodes that will be recorded live (in order, without duplicates);
    ``modality_of``: each model's default modality, which places a cassette.

    :param specs: The run's episodes.
    :param cassettes: The cassette folder.
    :param record_mode: The run's record mode.
    :param holds: Whether the store already holds an episode (it will not run).
    :param modality_of: Model name -> default modality; None for each spec's own.
    :returns: Model -> its live episodes; models without one left out.
    """
    grid: dict[str, list[EpisodeSpec]] = {}
    for spec in dict.fromkeys(specs):
        live = is_live(spec, cassettes=cassettes, record_mode=record_mode, modality_of=modality_of)
        if live and not holds(spec):
            grid.setdefault(spec.model, []).append(spec)
    return grid


def preflight_live(
    grid: Mapping[str, Sequence[EpisodeSpec]], registry: Any, models_file: Path | None = None
) -> list[PreflightReport]:
    """One preflight per model of ``grid``, estimating exactly its live episodes
    (``models_file``: the user registry, named in the check-again command).

    :param grid: Model -> its live episodes (:func:`live_grid`).
    :param registry: The model registry.
    :param models_file: The user registry file, if any.
    :returns: One :class:`PreflightReport` per model.
    """
    where = None if models_file is None else str(models_file)
    return [
        preflight(registry.get(model), specs[0], episodes=len(specs), models_file=where)
        for model, specs in grid.items()
    ]


@dataclass
class SessionPreflight:
    """A session's preflights: each model at most once, only for episodes recorded live."""

    registry: Any
    _: KW_ONLY
    cassettes: Path
    record_mode: str
    holds: Callable[[EpisodeSpec], bool]
    enabled: bool = True
    models_file: Path | None = None
    checked: set[str] = field(default_factory=set, init=False)

    def run(self, specs: Iterable[EpisodeSpec]) -> tuple[list[PreflightReport], int]:
        """Reports for the models not checked yet (none when disabled), and how many live
        episodes they have."""
        grid = live_grid(
            specs,
            cassettes=self.cassettes,
            record_mode=self.record_mode,
            holds=self.holds,
            modality_of=lambda model: str(self.registry.get(model).modality),
        )
        grid = {model: mine for model, mine in grid.items() if model not in self.checked}
        self.checked.update(grid)
        # Reference agents run in this process (nothing to get wrong), and a probe's made-up
        # history is no conversation their scripted state accepts (mimic answers it 400).
        remote = {
            model: mine
            for model, mine in grid.items()
            if self.registry.get(model).provider != "reference"
        }
        reports = preflight_live(remote, self.registry, self.models_file) if self.enabled else []
        return reports, sum(len(mine) for mine in grid.values())


#: The shape of an EMRD case or gate id inside a node id: ``[<model>-<condition>-...]``.
_EMRD_ID: Final = re.compile(r"\[(?P<id>[^\]]*-(?:" + "|".join(CONDITIONS) + r")-[^\]]*)\]$")


def params_of_node_ids(ids: Iterable[str], by_id: Callable[[], Mapping[str, Any]]) -> list[Any]:
    """The EMRD parameters (specs, gate cells) behind pytest node ids.

    For the pytest-xdist controller, which sees node ids, not items. ``by_id`` (called only
    when some id has an EMRD shape, so other sessions stay untouched) maps each case and
    gate id to its parameter; an id that combines it with other parameters
    (``[scout-baseline-office-ep00-fast]``) is matched on ``-`` boundaries.

    :param ids: pytest node ids.
    :param by_id: Returns case or gate id -> parameter; called at most once.
    :returns: The parameters found, in id order.
    """
    found = [m["id"] for i in ids if (m := _EMRD_ID.search(i))]
    if not found:
        return []
    table = by_id()
    params = []
    for key in found:
        if key in table:
            params.append(table[key])
        else:
            params += [p for k, p in table.items() if f"-{k}-" in f"-{key}-"]
    return params
