"""Version of the ai2thor backend's own part of the world."""

from typing import Final

THOR_VERSION: Final = "ai2thor-2"
"""The ProcTHOR house this backend builds, its navigation, visibility filtering and condition
calls: bump it when any of those change (recordings made on THOR are keyed by it).
``ai2thor-2``: the agent enters through ``metadata.agentPoses`` at a grid point; assets
chosen by footprint; visibility is THOR's ``visible`` flag with horizontal distances."""
