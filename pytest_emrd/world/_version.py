"""The built-in world's protocol version (cassettes are keyed by it)."""

from __future__ import annotations

from typing import Final

WORLD_VERSION: Final = "builtin-5"
"""Bump whenever layouts, rendering, visibility or feedback text change: a recorded cassette
holds frame digests and feedback strings. ``builtin-5``: furniture occludes; objects are
visible within 3.3 m (low light 1.65 m), landmarks and the frame reach 7 m (3.5 m); the 20
episodes of a spawn room start on 20 distinct points (``docs/interpretation/world.md``)."""
