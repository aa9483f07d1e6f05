"""The built-in world's protocol version (cassettes are keyed by it)."""

from __future__ import annotations

from typing import Final

WORLD_VERSION: Final = "builtin-5"
"""Bump whenever layouts, rendering, visibility or feedback text change: a recorded cassette
holds frame digests and feedback strings, so any such change must invalidate it.

* ``builtin-4`` — the paper protocol: one fixed office (:func:`~pytest_emrd.world.paper_office`)
  unless layouts are ``generated``; every layout has all four doorways; ``Term(r)`` always
  ends the episode (``r`` outside the four rooms is Other); no object id in ``vision``
  feedback, where ``Goto`` takes object types.
* ``builtin-5`` — the paper's "agents cannot scan rooms from doorways": furniture
  occludes (desks, tables, shelving, television, fridge, counters, armchairs); objects are
  visible within 3.3 m (low light 1.65 m), landmarks and the frame reach 7 m (3.5 m); the
  20 episodes of a spawn room start on 20 distinct points within 1 m of its centre (or
  the 20 free points nearest it)."""
