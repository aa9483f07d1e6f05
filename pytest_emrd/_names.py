"""Names that become path components, and paths that must stay inside their root (pure).

A model name is a cassette folder and part of every episode file name; a name that is not a
plain slug (``../../evil``, ``/tmp/x``) would write outside those roots, so names are checked
where they enter (registry, ``--emrd-model``) and every built path against its root.
"""

from __future__ import annotations

import os
import re
from pathlib import Path
from typing import Final

from pytest_emrd.errors import ConfigError

SLUG: Final = re.compile(r"^[A-Za-z0-9][A-Za-z0-9._-]{0,99}$")
"""A plain name: a letter or digit, then up to 99 letters, digits, ``.``, ``_`` or ``-``
(no separator, no leading dot, so never ``.`` or ``..``)."""
SLUG_RULE: Final = "use 1-100 letters, digits, '.', '_' or '-', starting with a letter or digit"


def check_slug(where: str, name: object, *, becomes: str) -> str:
    """``name`` if it is a slug, else a one-line :class:`ConfigError`: ``where`` names the
    file or option, ``becomes`` what the name is used as (``a cassette folder``)."""
    if not isinstance(name, str) or SLUG.match(name) is None:
        raise ConfigError(f"{where}: name {name!r} is not a plain name ({becomes}); {SLUG_RULE}.")
    return str(name)


def check_inside(root: Path, path: Path, *, what: str) -> Path:
    """``path`` if, once ``..`` and ``.`` are resolved lexically, it lies inside ``root`` and
    no part of it below ``root`` is a symbolic link (its real path is ``root``'s real path
    joined with the rest); else a one-line :class:`ConfigError`."""
    base = Path(os.path.normpath(os.path.abspath(root)))
    full = Path(os.path.normpath(os.path.abspath(path)))
    if full != base and base not in full.parents:
        raise ConfigError(
            f"{what} {path} lies outside {root}; model and file names must be plain names "
            f"({SLUG_RULE})."
        )
    real = Path(os.path.realpath(full))
    if real != Path(os.path.realpath(base)) / full.relative_to(base):
        raise ConfigError(
            f"{what} {path} is or lies under a symbolic link (to {real}); it is refused, never "
            f"opened, so that nothing is read or written outside {root}: replace the link with "
            "the real file or folder."
        )
    return path
