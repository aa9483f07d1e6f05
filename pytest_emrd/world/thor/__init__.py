"""The ``ai2thor`` backend: the shared EMRD layout built as a ProcTHOR house and driven
through ``ai2thor.controller.Controller`` (extra ``thor``: ``pip install
'pytest-emrd[thor]'``; needs a THOR build and, for CloudRendering, a GPU with Vulkan).

Actions, feedback text and the spawn pose are the builtin world's, so an agent and the
metrics see the same protocol on both backends. THOR frames are not bit-stable across
GPUs, drivers and builds: recordings made on this backend replay only with lenient
matching (``--emrd-matching lenient``).

Importing this package does not import ``ai2thor``; that happens when a
:class:`ThorSimulator` starts its controller.
"""

from __future__ import annotations

from pytest_emrd.world.thor._assets import SCHEMA, THOR_ROOM_TYPES, Asset, assets, choose_asset
from pytest_emrd.world.thor._house import build_house
from pytest_emrd.world.thor._ids import IdTable
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
