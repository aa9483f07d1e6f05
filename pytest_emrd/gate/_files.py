"""Reading a thresholds file from disk and checking its models against a registry."""

from __future__ import annotations

from collections.abc import Collection
from pathlib import Path
from typing import TYPE_CHECKING, Final

from pytest_emrd._yaml import read_text
from pytest_emrd.errors import EmrdError
from pytest_emrd.gate._thresholds import Thresholds, parse_thresholds

if TYPE_CHECKING:
    from pytest_emrd.agent import Registry

#: How to make a model of one's own registry known to every run (ends unknown-model errors).
REGISTER_MODEL_HINT: Final = (
    " A model of your own registry must be registered for every run that reads this file:"
    " set `emrd_models = FILE` in the pytest ini (or pass --emrd-models FILE), and"
    " --models FILE to `emrd gate` and `emrd report`."
)


def load_thresholds(path: Path, *, registry: Registry, metrics: Collection[str]) -> Thresholds:
    """Read and validate a thresholds file against a model registry (``registry.get``: parametric
    names such as ``scout-decay-8`` pass) and metric names; a missing file is a ConfigError.

    :param path: The ``thresholds.yaml``.
    :param registry: The models its gates may name.
    :param metrics: The metric names its gates may use.
    :returns: The validated :class:`Thresholds`.
    """

    def is_model(name: str) -> bool:
        try:
            registry.get(name)
        except EmrdError:
            return False
        return True

    text = read_text(
        path, what="thresholds file", flag="--emrd-thresholds (emrd gate --thresholds)"
    )
    return parse_thresholds(
        text,
        source=str(path),
        is_model=is_model,
        model_names=registry.names(),
        metrics=metrics,
        unknown_model_hint=REGISTER_MODEL_HINT,
    )
