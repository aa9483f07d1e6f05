"""One line for a file system failure: the path, what went wrong, and what to do (pure).

A full disk, a read-only folder or a file where a folder belongs end every ``emrd`` command
and pytest test in one line built here, never in a traceback.
"""

from __future__ import annotations

import errno
from typing import Final

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
