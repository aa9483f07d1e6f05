"""The ``ai2thor`` backend: the shared EMRD layout built as a ProcTHOR house and driven
through ``ai2thor.controller.Controller`` (extra ``thor``; ``docs/ai2thor.md``).

Actions, feedback text and the spawn pose are the builtin world's. THOR frames are not
bit-stable across GPUs, drivers and builds: recordings made on this backend replay only
with ``--emrd-matching lenient``. Importing this package does not import ``ai2thor``.
"""

from __future__ import annotations

from pytest_emrd.world.thor._assets import SCHEMA, THOR_ROOM_TYPES, Asset, assets, choose_asset
from pytest_emrd.world.thor._house import IdTable, build_house
from pytest_emrd.world.thor._simulator import DEFAULTS, ThorSimulator
from pytest_emrd.world.thor._version import THOR_VERSION

__all__ = [
    "DEFAULTS",
    "SCHEMA",
    "THOR_ROOM_TYPES",
    "THOR_VERSION",
    "Asset",
    "IdTable",
    "ThorSimulator",
    "assets",
    "build_house",
    "choose_asset",
]
