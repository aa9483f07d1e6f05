"""The built-in world's protocol version (cassettes are keyed by it)."""

from __future__ import annotations

from typing import Final

WORLD_VERSION: Final = "builtin-3"
"""Bump whenever layouts, rendering, visibility or feedback text change: a recorded cassette
holds frame digests and feedback strings, so any such change must invalidate it."""
