"""Simulator backends by name, imported lazily, and the world versions recordings are keyed by."""

from __future__ import annotations

import importlib
from collections.abc import Callable
from typing import Any, Final

from pytest_emrd.errors import check_choice, missing_extra
from pytest_emrd.world._model import Simulator

WORLD_VERSION: Final = "builtin-7"
"""Bump whenever layouts, rendering, visibility or feedback text change: a recorded cassette
holds frame digests and feedback strings. ``builtin-7``: a pixel is legible when it differs
from what the frame shows there without its object; fog is total at the visibility distance
(``docs/interpretation/world.md``)."""


def _builtin(**options: Any) -> Simulator:
    from pytest_emrd.world._simulator import BuiltinSimulator

    return BuiltinSimulator(**options)


def _ai2thor(**options: Any) -> Simulator:
    try:
        module = importlib.import_module("pytest_emrd.world.thor")
    except ImportError as exc:
        if (exc.name or "").split(".")[0] == "ai2thor":
            raise missing_extra("ai2thor", "thor") from exc
        raise
    simulator: Simulator = module.ThorSimulator(**options)
    return simulator


BACKENDS: Final[dict[str, Callable[..., Simulator]]] = {"builtin": _builtin, "ai2thor": _ai2thor}


def make_simulator(backend: str = "builtin", **options: Any) -> Simulator:
    """A new simulator of ``backend`` (``builtin`` or ``ai2thor``) built with ``options``.

    :param backend: A name of :data:`BACKENDS`.
    :param options: Keyword arguments of the backend's simulator.
    :returns: A fresh :class:`Simulator`.
    """
    check_choice(
        "backend", backend, BACKENDS, hint="Use --emrd-backend builtin for the numpy world."
    )
    return BACKENDS[backend](**options)


def world_version(backend: str = "builtin") -> str:
    """The world version a recording on ``backend`` depends on: for ``ai2thor`` joined with the
    builtin one, whose layouts, spawns and wording THOR episodes use (``ai2thor-2+builtin-7``).

    :param backend: The backend the recording ran on.
    :returns: The version string cassettes are keyed on.
    """
    check_choice("backend", backend, BACKENDS)
    if backend == "builtin":
        return WORLD_VERSION
    from pytest_emrd.world.thor._version import THOR_VERSION

    return f"{THOR_VERSION}+{WORLD_VERSION}"
