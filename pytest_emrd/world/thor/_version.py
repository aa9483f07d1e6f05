"""Version of the ai2thor backend's own part of the world."""

from typing import Final

THOR_VERSION: Final = "ai2thor-2"
"""The ProcTHOR house this backend builds, its navigation, visibility filtering and condition
calls. Bump it when any of those change: recordings made on THOR are keyed by it.

* ``ai2thor-1`` — first house and navigation.
* ``ai2thor-2`` — the agent enters through ``metadata.agentPoses`` at a grid point; asset
  ids from the ProcTHOR database chosen by footprint and placed at their bounding-box
  height inside their room; teleports at the height THOR returns; visibility is THOR's
  ``visible`` flag alone, with horizontal distances; ``low_light`` also dims the skybox.
"""
