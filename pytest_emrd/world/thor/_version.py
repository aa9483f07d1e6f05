"""Version of the ai2thor backend's own part of the world."""

from typing import Final

THOR_VERSION: Final = "ai2thor-1"
"""The ProcTHOR house this backend builds, its navigation, visibility filtering and condition
calls. Bump it when any of those change: recordings made on THOR are keyed by it."""
