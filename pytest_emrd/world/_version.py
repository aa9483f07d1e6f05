"""The built-in world's protocol version (cassettes are keyed by it)."""

from __future__ import annotations

from typing import Final

WORLD_VERSION: Final = "builtin-4"
"""Bump whenever layouts, rendering, visibility or feedback text change: a recorded cassette
holds frame digests and feedback strings, so any such change must invalidate it.

* ``builtin-4`` — the paper protocol: one fixed office (:func:`~pytest_emrd.world.paper_office`)
  unless layouts are ``generated``; every layout has all four doorways; ``Term(r)`` always
  ends the episode (``r`` outside the four rooms is Other); no object id in ``vision``
  feedback, where ``Goto`` takes object types."""
