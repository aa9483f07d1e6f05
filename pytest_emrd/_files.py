"""Files and folders: plain names, paths kept inside their roots, atomic writes, and one
line for a file system failure (pure but for the writes).

A model name is a cassette folder and part of every episode file name; a name that is not a
plain slug (``../../evil``, ``/tmp/x``) would write outside those roots, so names are checked
where they enter (registry, ``--emrd-model``) and every built path against its root. A full
disk, a read-only folder or a file where a folder belongs end every ``emrd`` command and
pytest test in one line built here, never in a traceback.
"""

from __future__ import annotations

import errno
import os
import re
import tempfile
from pathlib import Path
from typing import Final

from pytest_emrd.errors import ConfigError


def write_bytes_atomic(path: Path, data: bytes, *, temp: Path | None = None) -> None:
    """Write ``data`` to ``path`` via ``<temp>.<random>.tmp`` (``temp`` on the same file
    system; default ``.<name>`` beside ``path``) and a rename, with the usual permissions
    (``0o666`` minus the umask), not ``mkstemp``'s 0600."""
    path.parent.mkdir(parents=True, exist_ok=True)
    temp = temp or path.with_name(f".{path.name}")
    fd, tmp = tempfile.mkstemp(prefix=f"{temp.name}.", suffix=".tmp", dir=temp.parent)
    try:
        with os.fdopen(fd, "wb") as handle:
            handle.write(data)
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o666 & ~umask)
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


_FIXES: Final = {
    errno.ENOSPC: "the disk is full; free some space",
    errno.EDQUOT: "the disk quota is used up; free some space",
    errno.EROFS: "the file system is read-only; use a writable folder",
    errno.EACCES: "permission denied; make the folder writable (chmod u+w) or use another one",
    errno.EPERM: "permission denied; make the folder writable (chmod u+w) or use another one",
    errno.ENOTDIR: "a part of the path is a file, not a folder; move that file away or use "
    "another folder",
    errno.EISDIR: "the path is a folder where a file belongs; move that folder away",
    errno.ENOENT: "it does not exist; create it or use another path",
    errno.EEXIST: "a file is in the way where a folder belongs; move it away or use another folder",
}


def os_error_line(exc: OSError, *, doing: str, path: object = None, option: str = "") -> str:
    """``cannot <doing> <path>: <fix>[ (<option>)].``: ``doing`` is ``write`` or ``read``;
    ``path`` the file meant (default: the one the error names; a temporary file's name
    says less), ``option`` the flag that picks the path (``--emrd-results DIR``)."""
    path = path if path is not None else exc.filename if exc.filename is not None else "a file"
    fix = _FIXES.get(exc.errno or 0) or f"{exc.strerror or type(exc).__name__}; check the path"
    where = f" ({option})" if option else ""
    return f"cannot {doing} {path}: {fix}{where}."


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
